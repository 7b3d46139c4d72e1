# Session 18, third run: the megakernel turn's round trips (the targets' ticket and budget
# atomics issued together, every queue's count read with the stop word). schedbench / reyes-prev
# = commit 7110587 (before), schedbench-exp / reyes = this change. A chain (one root, fan-out 1,
# depth 2000) measures one turn's latency: GPU time / 2001 turns.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
K=$B/data/rib/killeroo.rib
q() { python3 scripts/h200/medians.py "$1" "$2"; }
for rep in 1 2; do
 for v in before after; do S=$B/schedbench-exp; [ $v = before ] && S=$B/schedbench
  n=chain-$v-$rep
  timeout 120 $S --workload tree --roots 1 --fanout fixed:1 --depth 2000 --strategy all --runs 5 --json > $R/$n.jsonl 2> $R/$n.log
  q $R/$n.jsonl $n >> $R/table.txt
  for p in binary large-payload irregular deep heavy-work; do
    n=tree-$p-$v-$rep
    timeout 120 $S --workload tree --preset $p --strategy all --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
    q $R/$n.jsonl $n >> $R/table.txt
    timeout 120 $S --workload tree --preset $p --strategy megakernel --policy fifo --runs 10 --json > $R/$n-fifo.jsonl 2> $R/$n-fifo.log
    q $R/$n-fifo.jsonl $n-fifo >> $R/table.txt
  done
 done
done
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for rep in 1 2; do for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$K
  n=$bin-$sc-megakernel-$rep
  timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy megakernel --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
  echo "$n $(med $R/$n.json)" >> $R/frames.txt
done; done; done
(cd $R && md5sum *.png > md5.txt)
WGPU_ADAPTER_NAME=H200 timeout 200 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/table.txt $R/frames.txt $R/tests.txt; grep 'test result' $R/scheduler_gpu.txt
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
