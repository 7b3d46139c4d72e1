# Session 17, third run: the raster peer after its tessellation was spread over the GPU
# (tiles of 64 grid points), and frames before/after with displacement merged (reyes-prev =
# f72f1a6; Killeroo's `Attribute "displacementbound"` is read now), and the rasterization
# modes (issue 14 item 2: bbox against nearest, Killeroo and teapot, two micropolygon sizes).
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
K=$B/data/rib/killeroo.rib; U=$B/data/rib/uteapot.rib
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f %.3f' % (r['gpu_ms']['median'], r['wall_ms']['median']))" $1 2>/dev/null; }
for sc in teapot uteapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$K; [ $sc = uteapot ] && S=$U
  for size in 1920x1080 3840x2160; do W=${size%x*}; H=${size#*x}; n=bench-$sc-$size
    timeout 150 $B/reyes bench $S --width $W --height $H --strategy megakernel --frames 100 --turntable --peer raster --json > $R/$n.json 2> $R/$n.log
    python3 - $R/$n.json $n >> $R/bench.txt 2>&1 <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); g = d['gpu_ms'] or {}; p = d.get('peer') or {}
pg = p.get('gpu_ms') or {}; diff = p.get('difference') or [{}]
print(sys.argv[2], 'reyes wall %.3f gpu %.3f fps %.0f | peer wall %.3f gpu %.3f fps %.0f tris %.0f psnr %.1f over %.4f' % (
  d['wall_ms']['median'], g.get('median', -1), d['fps'],
  p['wall_ms']['median'], pg.get('median', -1), p['fps'], p['triangles']['median'],
  diff[0].get('psnr_db') or 0, diff[0].get('over')))
PY
  done
done
for rep in 1 2 3; do
 for bin in reyes-prev reyes; do
  for sc in teapot killeroo; do
   S=teapot; [ $sc = killeroo ] && S=$K
   for st in megakernel multipass; do
     n=$bin-$sc-$st-$rep
     timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
     echo "$n $(med $R/$n.json)" >> $R/frames.txt
   done
  done
 done
done
for sc in teapot killeroo; do S=teapot; [ $sc = killeroo ] && S=$K
  for s in 1 0.5; do for m in bbox nearest; do n=raster-$sc-$s-$m
    timeout 120 $B/reyes bench $S --width 1920 --height 1080 --mp-size $s --raster $m --frames 100 --json > $R/$n.json 2> $R/$n.log
    python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(sys.argv[2], 'wall %.3f gpu %.3f fps %.0f' % (d['wall_ms']['median'], d['gpu_ms']['median'], d['fps']))" $R/$n.json $n >> $R/raster.txt 2>&1
  done; done
done
md5sum $R/*.png > $R/md5.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/bench.txt $R/frames.txt $R/raster.txt; awk '{print $1}' $R/md5.txt | sort | uniq -c
