# Session 18, last run: the final main on the H200: the scheduler's GPU tests, the trees, and
# Reyes frames against reyes-prev (the build after the motion-blur merge, before the start-up
# and trial changes), images compared by md5.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
K=$B/data/rib/killeroo.rib
WGPU_ADAPTER_NAME=H200 timeout 200 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
for p in binary irregular deep large-payload heavy-work; do
  timeout 120 $B/schedbench-exp --workload tree --preset $p --strategy all --runs 10 --json > $R/tree-$p.jsonl 2> $R/tree-$p.log
  python3 scripts/h200/medians.py $R/tree-$p.jsonl tree-$p >> $R/table.txt
done
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$K
  for st in megakernel multipass multipass-host; do n=$bin-$sc-$st
    timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    echo "$n $(med $R/$n.json)" >> $R/frames.txt
  done; done; done
(cd $R && md5sum *.png > md5.txt)
cat $R/table.txt $R/frames.txt $R/tests.txt; grep 'test result' $R/scheduler_gpu.txt
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
