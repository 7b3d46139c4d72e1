# Session 16: Reyes frames before (reyes-prev, last session's) / after (rational items, partial
# rounds, primvars); rational scenes; 1M and 2M patches; budgets; overflow; queue tests.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv > $R/gpu.txt
K=$B/data/rib/killeroo.rib
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f %.3f' % (r['gpu_ms']['median'], r['wall_ms']['median']))" $1 2>/dev/null; }
for rep in 1 2; do
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
for st in megakernel multipass multipass-host; do
  n=budget64k-$st; /usr/bin/time -f "%e s" -o $R/$n.time timeout 120 $B/reyes render teapot --width 1920 --height 1080 --memory-budget 64K --strategy $st -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1; echo "$n $(cat $R/$n.time) rc=$?" >> $R/frames.txt
done
for sc in teapot killeroo; do S=teapot; [ $sc = killeroo ] && S=$K
  for st in megakernel multipass; do n=bench-$sc-$st
    timeout 120 $B/reyes bench $S --width 1920 --height 1080 --strategy $st --frames 200 --turntable --json > $R/$n.json 2> $R/$n.log
    python3 -c "import json,sys; d=json.load(open(sys.argv[1])); g=d['gpu_ms'] or {}; print(sys.argv[2], 'wall', round(d['wall_ms']['median'],3), round(d['wall_ms']['p95'],3), 'gpu', round(g.get('median',-1),3), round(g.get('p95',-1),3), 'fps', round(d['fps'],1), 'rerendered', d['rerendered'], 'pipelined', d['pipelined'])" $R/$n.json $n >> $R/bench.txt 2>&1
  done
done
for sz in "1000 1000" "2000 1000"; do set -- $sz; N=$(($1*$2))
  python3 $B/many.py /tmp/many.rib $1 $2
  for st in megakernel multipass multipass-host; do
    n=many$N-$st; /usr/bin/time -f "%e s %M KB" -o $R/$n.time timeout 150 $B/reyes render /tmp/many.rib --strategy $st --runs 3 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    echo "$n rc=$? $(cat $R/$n.time) $(med $R/$n.json)" >> $R/many.txt
  done
  n=many$N-cpu; /usr/bin/time -f "%e s %M KB" -o $R/$n.time timeout 150 $B/reyes render /tmp/many.rib --cpu -o $R/$n.png > $R/$n.log 2>&1; echo "$n rc=$? $(cat $R/$n.time)" >> $R/many.txt
done
rm -f /tmp/many.rib
timeout 240 $B/schedbench --workload tree --strategy all --runs 5 --seed 32 --depth 15 --fanout uniform:4 --roots 45 --workgroups 485 --capacity 16 > $R/overflow-16.txt 2>&1
timeout 240 $B/schedbench --workload tree --strategy all --runs 5 --seed 32 --depth 15 --fanout uniform:4 --roots 45 --workgroups 485 > $R/overflow-roomy.txt 2>&1
timeout 300 $B/scheduler_gpu > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/scheduler_gpu.txt
md5sum $R/*.png > $R/md5.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/frames.txt $R/bench.txt $R/many.txt; tail -2 $R/scheduler_gpu.txt; grep -h -A6 "^strategy" $R/overflow-16.txt | head -12
