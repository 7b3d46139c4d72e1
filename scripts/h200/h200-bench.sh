# reyes bench (issue 12 item 1): pipelined frames, wall against GPU ms, teapot / uteapot /
# killeroo at 1920x1080 and 3840x2160, both strategies; the old path (`render --runs 10`) beside.
# Needs .devbin/reyes built from the bench branch and .devbin/data/rib/{killeroo,uteapot}.rib.
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/bench; mkdir -p $R
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv > $R/gpu.txt
for sc in teapot uteapot killeroo; do
  S=teapot; [ $sc != teapot ] && S=$B/data/rib/$sc.rib
  for size in "1920 1080" "3840 2160"; do set -- $size
    for st in megakernel multipass; do
      n=$sc-$1x$2-$st
      timeout 120 $B/reyes bench $S --width $1 --height $2 --strategy $st --frames 200 \
        --turntable --json > $R/$n.json 2> $R/$n.log
      echo "$n rc=$?" >> $R/rc.txt
      python3 -c "import json,sys; d=json.load(open(sys.argv[1])); g=d['gpu_ms'] or {}; \
print(sys.argv[2], 'wall', round(d['wall_ms']['median'],3), round(d['wall_ms']['p95'],3), \
'gpu', round(g.get('median',-1),3), round(g.get('p95',-1),3), 'fps', round(d['fps'],1), \
'rerendered', d['rerendered'], 'pipelined', d['pipelined'])" $R/$n.json $n >> $R/summary.txt 2>&1
    done
  done
done
# The old path at 1080p for comparison (wall 31-73 ms in issue 12).
timeout 120 $B/reyes render $B/data/rib/killeroo.rib --width 1920 --height 1080 --runs 10 \
  -o $R/render-killeroo.png --stats $R/render-killeroo.json > $R/render-killeroo.log 2>&1
# The last frame as an image, for a look.
timeout 120 $B/reyes bench $B/data/rib/killeroo.rib --width 1920 --height 1080 --frames 20 \
  --turntable -o $R/bench-killeroo.png > $R/bench-killeroo.txt 2>&1
cat $R/rc.txt $R/summary.txt $R/bench-killeroo.txt
