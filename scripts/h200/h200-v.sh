# Session 19, final build: item layout chosen per program (planar for one-thread items of 16+
# words on a GPU); every tree preset on every strategy, large items also forced interleaved in
# the same run; Reyes frames (interleaved by the rule) against reyes-prev (session 18's main),
# images by md5; the scheduler's and the real-time renderer's GPU tests.
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/v; mkdir -p $R
timeout 200 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
RUST_BACKTRACE=0 timeout 200 $B/reyes_realtime --test-threads 1 > $R/reyes_realtime.txt 2>&1; echo "reyes_realtime rc=$?" >> $R/tests.txt
for p in binary irregular deep large-payload heavy-work; do
  timeout 120 $B/schedbench --workload tree --preset $p --strategy all --runs 10 --json > $R/tree-$p.jsonl 2> $R/tree-$p.log
  python3 scripts/h200/medians.py $R/tree-$p.jsonl tree-$p >> $R/table.txt
done
timeout 120 $B/schedbench --workload tree --preset large-payload --strategy all --item-layout interleaved --runs 10 --json > $R/tree-lp-i.jsonl 2> $R/tree-lp-i.log
python3 scripts/h200/medians.py $R/tree-lp-i.jsonl large-payload-interleaved >> $R/table.txt
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$B/data/rib/killeroo.rib
  for st in megakernel multipass multipass-host; do n=$bin-$sc-$st
    timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    echo "$n $(med $R/$n.json)" >> $R/frames.txt
  done; done; done
(cd $R && md5sum *.png > md5.txt)
cat $R/table.txt $R/frames.txt $R/tests.txt; grep 'test result' $R/scheduler_gpu.txt $R/reyes_realtime.txt
grep -E "^test |panicked" $R/reyes_realtime.txt | cut -c1-200
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
cd $OUT && tar czf v.tgz --exclude='*.png' v && rm -rf v
