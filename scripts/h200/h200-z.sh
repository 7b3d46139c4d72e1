# Session 19, last: the final reyes (metal surfaces) against reyes-prev on the H200: frames and
# md5 of teapot and Killeroo, and the field airplane (metal) on the GPU and the CPU twin (counts).
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/z; mkdir -p $R
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f' % r['gpu_ms']['median'])" $1 2>/dev/null; }
for bin in reyes-prev reyes; do for sc in teapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$B/data/rib/killeroo.rib
  for st in megakernel multipass-host; do n=$bin-$sc-$st
    timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    echo "$n $(med $R/$n.json)" >> $R/frames.txt
  done; done; done
timeout 120 $B/reyes render $B/data/airplane.rib --strategy megakernel -o $R/air-gpu.png > $R/air.log 2>&1
timeout 120 $B/reyes render $B/data/airplane.rib --cpu -o $R/air-cpu.png >> $R/air.log 2>&1
(cd $R && md5sum *.png > md5.txt)
cat $R/frames.txt $R/air.log
for sc in teapot killeroo; do echo "$sc distinct md5: $(grep -- "-$sc-" $R/md5.txt | awk '{print $1}' | sort -u | wc -l)"; done
cd $OUT && tar czf z.tgz --exclude='reyes*.png' z && rm -rf z
