# Session 19: the megakernel enqueueing straight into the slots (a ticket per item, the batch's
# tickets listed in workgroup memory) against through the outbox; trees alternated D O D O,
# then every strategy once; Reyes frames against reyes-prev (outbox, session 18), images by md5;
# the scheduler's and the real-time renderer's GPU tests.
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/w; mkdir -p $R
timeout 200 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
RUST_BACKTRACE=0 timeout 200 $B/reyes_realtime --test-threads 1 > $R/reyes_realtime.txt 2>&1; echo "reyes_realtime rc=$?" >> $R/tests.txt
for p in binary irregular deep large-payload heavy-work; do for rep in 1 2; do for e in direct outbox; do
  n=$p-$e-$rep
  timeout 60 $B/schedbench --workload tree --preset $p --strategy megakernel --enqueue $e --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
  python3 scripts/h200/medians.py $R/$n.jsonl $n >> $R/table.txt
done; done; done
for p in binary irregular deep large-payload heavy-work; do
  timeout 120 $B/schedbench --workload tree --preset $p --strategy all --runs 10 --json > $R/tree-$p.jsonl 2> $R/tree-$p.log
  python3 scripts/h200/medians.py $R/tree-$p.jsonl all-$p >> $R/table.txt
done
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for rep in 1 2; do for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$B/data/rib/killeroo.rib
  n=$bin-$sc-mk-$rep
  timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy megakernel --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
  echo "$n $(med $R/$n.json)" >> $R/frames.txt
  done
  n=$bin-bench-killeroo-$rep
  timeout 120 $B/$bin bench $B/data/rib/killeroo.rib --width 1920 --height 1080 --strategy megakernel --frames 200 --turntable --json > $R/$n.json 2> $R/$n.log
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(sys.argv[2], 'wall', round(d['wall_ms']['median'],3), 'gpu', round(d['gpu_ms']['median'],3), 'fps', round(d['fps'],1))" $R/$n.json $n >> $R/frames.txt 2>&1
done; done
(cd $R && md5sum *.png > md5.txt)
cat $R/table.txt $R/frames.txt $R/tests.txt; grep 'test result' $R/scheduler_gpu.txt $R/reyes_realtime.txt
grep -E "^test .*FAILED|panicked" $R/reyes_realtime.txt | cut -c1-200
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
cd $OUT && tar czf w.tgz --exclude='*.png' w && rm -rf w
