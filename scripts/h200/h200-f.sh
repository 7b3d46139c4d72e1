# Session 16, second run: frames before (reyes-prev, last session's) / after (224-byte items
# again: lean-items), reyes bench at 1080p and 4K, rational scenes, 2M patches, queue tests.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv > $R/gpu.txt
K=$B/data/rib/killeroo.rib
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f %.3f' % (r['gpu_ms']['median'], r['wall_ms']['median']))" $1 2>/dev/null; }
for rep in 1 2 3; do
 for bin in reyes-prev reyes; do
  for sc in teapot killeroo; do
   S=teapot; [ $sc = killeroo ] && S=$K
   for st in megakernel multipass multipass-host; do
     n=$bin-$sc-$st-$rep
     timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
     echo "$n $(med $R/$n.json)" >> $R/frames.txt
   done
  done
 done
done
for sc in nurbs-sphere-order3 airplane; do for st in megakernel multipass; do
  n=new-$sc-$st; timeout 120 $B/reyes render $B/data/$sc.rib --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1; echo "$n $(med $R/$n.json)" >> $R/frames.txt
done; done
for sc in teapot uteapot killeroo; do S=teapot; [ $sc != teapot ] && S=$B/data/rib/$sc.rib
 for size in "1920 1080" "3840 2160"; do set -- $size
  for st in megakernel multipass; do n=bench-$sc-$1x$2-$st
    timeout 120 $B/reyes bench $S --width $1 --height $2 --strategy $st --frames 200 --turntable --json > $R/$n.json 2> $R/$n.log
    python3 -c "import json,sys; d=json.load(open(sys.argv[1])); g=d['gpu_ms'] or {}; print(sys.argv[2], 'wall', round(d['wall_ms']['median'],3), round(d['wall_ms']['p95'],3), 'gpu', round(g.get('median',-1),3), round(g.get('p95',-1),3), 'fps', round(d['fps'],1), 'rerendered', d['rerendered'], 'pipelined', d['pipelined'])" $R/$n.json $n >> $R/bench.txt 2>&1
  done
 done
done
python3 $B/many.py /tmp/many.rib 2000 1000
for st in megakernel multipass-host; do
  n=many2000000-$st; /usr/bin/time -f "%e s %M KB" -o $R/$n.time timeout 150 $B/reyes render /tmp/many.rib --strategy $st --runs 3 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
  echo "$n rc=$? $(cat $R/$n.time) $(med $R/$n.json)" >> $R/many.txt
done
rm -f /tmp/many.rib
timeout 300 $B/scheduler_gpu > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/scheduler_gpu.txt
md5sum $R/*.png > $R/md5.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/frames.txt $R/bench.txt $R/many.txt; tail -2 $R/scheduler_gpu.txt
