# Session 19, final build: trees (leaves folded per workgroup step) on every strategy, against
# schedbench-prev (direct enqueue, leaves folded per leaf) alternated P N P N; Reyes frames of
# the merged build (direct enqueue, one dicing call site) against reyes-prev (session 18's main)
# by md5; the scheduler's and the real-time renderer's GPU tests.
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/x; mkdir -p $R
timeout 200 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
RUST_BACKTRACE=0 timeout 200 $B/reyes_realtime --test-threads 1 > $R/reyes_realtime.txt 2>&1; echo "reyes_realtime rc=$?" >> $R/tests.txt
for p in binary irregular deep large-payload heavy-work; do for rep in 1 2; do for bin in schedbench-prev schedbench; do
  n=$p-$bin-$rep
  timeout 120 $B/$bin --workload tree --preset $p --strategy all --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
  python3 scripts/h200/medians.py $R/$n.jsonl $n >> $R/table.txt
done; done; done
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$B/data/rib/killeroo.rib
  for st in megakernel multipass multipass-host; do n=$bin-$sc-$st
    timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    echo "$n $(med $R/$n.json)" >> $R/frames.txt
  done; done
  n=$bin-bench-killeroo
  timeout 120 $B/$bin bench $B/data/rib/killeroo.rib --width 1920 --height 1080 --strategy megakernel --frames 200 --turntable --json > $R/$n.json 2> $R/$n.log
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(sys.argv[2], 'wall', round(d['wall_ms']['median'],3), 'gpu', round(d['gpu_ms']['median'],3), 'fps', round(d['fps'],1))" $R/$n.json $n >> $R/frames.txt 2>&1
done
(cd $R && md5sum *.png > md5.txt)
cat $R/table.txt $R/frames.txt $R/tests.txt; grep 'test result' $R/scheduler_gpu.txt $R/reyes_realtime.txt
grep -E "^test .*FAILED|panicked" $R/reyes_realtime.txt | cut -c1-200
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
cd $OUT && tar czf x.tgz --exclude='*.png' x && rm -rf x
