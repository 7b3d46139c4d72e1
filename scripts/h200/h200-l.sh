# Session 18, second run: items moved 16 bytes at a time (vec4 accessors, 16-byte aligned
# regions) and the tree bodies' `var` item copy. schedbench = session 17's main (before),
# schedbench-exp = this change (EXP_TREE=unroll: payload loops unrolled in the source; else a
# loop). Then Reyes frames before/after (reyes-prev = session 17's main), and the scheduler's
# GPU tests on the H200.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
K=$B/data/rib/killeroo.rib
q() { python3 scripts/h200/medians.py "$1" "$2"; }
for rep in 1 2; do
for p in large-payload binary irregular deep heavy-work; do
  for v in before loop unroll; do
    n=tree-$p-$v-$rep; S=$B/schedbench-exp; [ $v = before ] && S=$B/schedbench
    EXP_TREE=$v timeout 120 $S --workload tree --preset $p --strategy all --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
    q $R/$n.jsonl $n >> $R/table.txt
    EXP_TREE=$v timeout 120 $S --workload tree --preset $p --strategy megakernel --policy fifo --runs 10 --json > $R/$n-fifo.jsonl 2> $R/$n-fifo.log
    q $R/$n-fifo.jsonl $n-fifo >> $R/table.txt
  done
done
done
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for rep in 1 2; do for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$K
  for st in megakernel multipass multipass-host; do n=$bin-$sc-$st-$rep
    timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    echo "$n $(med $R/$n.json)" >> $R/frames.txt
  done; done; done; done
(cd $R && md5sum *.png > md5.txt)
WGPU_ADAPTER_NAME=H200 timeout 200 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
WGPU_ADAPTER_NAME=H200 timeout 100 $B/workloads_gpu --test-threads 1 > $R/workloads_gpu.txt 2>&1; echo "workloads_gpu rc=$?" >> $R/tests.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/table.txt $R/frames.txt $R/tests.txt; grep 'test result' $R/scheduler_gpu.txt $R/workloads_gpu.txt
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
