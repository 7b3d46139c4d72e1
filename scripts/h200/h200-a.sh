# Part A: Reyes frames before/after (alternating processes), scheduler trees, overflow.
source .devbin/setup.sh
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv > $OUT/gpu.txt
K=$B/data/rib/killeroo.rib
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print(r['gpu_ms']['median'] if 'median' in r['gpu_ms'] else '', r['wall_ms']['median'] if 'median' in r['wall_ms'] else '')" $1 2>/dev/null; }
for rep in 1 2; do
 for bin in reyes-base reyes; do
  for sc in teapot killeroo; do
   S=teapot; [ $sc = killeroo ] && S=$K
   for st in megakernel multipass; do
     n=$bin-$sc-$st-$rep
     timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $OUT/$n.png --stats $OUT/$n.json > $OUT/$n.log 2>&1
     echo "$n $(med $OUT/$n.json)" >> $OUT/frames.txt
   done
  done
 done
done
for sc in teapot killeroo; do S=teapot; [ $sc = killeroo ] && S=$K
  n=reyes-$sc-multipass-host; timeout 120 $B/reyes render $S --width 1920 --height 1080 --strategy multipass-host --runs 10 -o $OUT/$n.png --stats $OUT/$n.json > $OUT/$n.log 2>&1; echo "$n $(med $OUT/$n.json)" >> $OUT/frames.txt
done
for st in megakernel multipass; do n=wall-$st; timeout 120 $B/reyes render $B/wall-beside-camera.rib --width 1920 --height 1080 --strategy $st --runs 10 -o $OUT/$n.png --stats $OUT/$n.json > $OUT/$n.log 2>&1; echo "$n $(med $OUT/$n.json)" >> $OUT/frames.txt; done
md5sum $OUT/*.png > $OUT/md5.txt
# Scheduler trees: every strategy in one invocation per preset.
for p in binary irregular deep large-payload heavy-work; do
  timeout 240 $B/schedbench --workload tree --preset $p --strategy all --runs 10 > $OUT/tree-$p.txt 2>&1
done
timeout 240 $B/schedbench --workload tree --strategy all --runs 5 --seed 32 --depth 15 --fanout uniform:4 --roots 45 --workgroups 485 --capacity 16 > $OUT/overflow-16.txt 2>&1
timeout 240 $B/schedbench --workload tree --strategy all --runs 5 --seed 32 --depth 15 --fanout uniform:4 --roots 45 --workgroups 485 > $OUT/overflow-roomy.txt 2>&1
cat $OUT/frames.txt; grep -h -A12 "^strategy" $OUT/tree-binary.txt $OUT/overflow-16.txt $OUT/overflow-roomy.txt | head -60
