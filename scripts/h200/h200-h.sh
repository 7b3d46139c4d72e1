# Session 17 (2026-12-01): reyes bench with the raster peer (issue 12: teapot, uteapot, Killeroo
# at 1080p and 4K, both strategies and the peer, one invocation each), frames before/after
# (reyes-prev = the session's starting commit f72f1a6; 5% rule), the device-driven multi-pass
# overflow (capacity 16 against room enough), the scheduler's GPU tests.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv > $R/gpu.txt
K=$B/data/rib/killeroo.rib; U=$B/data/rib/uteapot.rib
med() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['runs']; print('%.3f %.3f' % (r['gpu_ms']['median'], r['wall_ms']['median']))" $1 2>/dev/null; }
# 1. reyes bench, Reyes and the raster peer side by side.
for sc in teapot uteapot killeroo; do
  S=teapot; [ $sc = killeroo ] && S=$K; [ $sc = uteapot ] && S=$U
  for size in 1920x1080 3840x2160; do W=${size%x*}; H=${size#*x}
    for st in megakernel multipass; do n=bench-$sc-$size-$st
      timeout 150 $B/reyes bench $S --width $W --height $H --strategy $st --frames 100 --turntable --peer raster --json > $R/$n.json 2> $R/$n.log
      python3 - $R/$n.json $n >> $R/bench.txt 2>&1 <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); g = d['gpu_ms'] or {}; p = d.get('peer') or {}
pg = p.get('gpu_ms') or {}; diff = p.get('difference') or [{}]
print(sys.argv[2], 'reyes wall %.3f gpu %.3f fps %.0f rerendered %s | peer wall %.3f gpu %.3f fps %.0f msaa %s/%s tris %.0f psnr %s over %s' % (
  d['wall_ms']['median'], g.get('median', -1), d['fps'], d['rerendered'],
  p.get('wall_ms', {}).get('median', -1), pg.get('median', -1), p.get('fps', -1),
  p.get('msaa_samples'), p.get('msaa_wanted'), p.get('triangles', {}).get('median', -1),
  diff[0].get('psnr_db'), diff[0].get('over')))
PY
    done
  done
done
# 2. Frames before/after (3 alternating repetitions).
for rep in 1 2 3; do
 for bin in reyes-prev reyes; do
  for sc in teapot killeroo; do
   S=teapot; [ $sc = killeroo ] && S=$K
   for st in megakernel multipass; do
     n=$bin-$sc-$st-$rep
     timeout 120 $B/$bin render $S --width 1920 --height 1080 --strategy $st --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
     echo "$n $(med $R/$n.json)" >> $R/frames.txt
   done
  done
 done
done
# 3. The capacity-16 overflow, every strategy.
for cap in "" "--capacity 16"; do
  timeout 200 $B/schedbench --workload tree --strategy all --runs 5 --seed 32 --depth 15 --fanout uniform:4 --roots 45 --workgroups 485 $cap --json > $R/overflow${cap:+-16}.jsonl 2> $R/overflow${cap:+-16}.log
  python3 - $R/overflow${cap:+-16}.jsonl "cap${cap:+16}" >> $R/overflow.txt <<'PY'
import json, sys, statistics as st
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith('{')]
by = {}
for r in rows: by.setdefault(r['strategy'], []).append(r)
for s, rs in by.items():
  print(sys.argv[2], s, 'gpu %.3f wall %.3f launches %d submits %s growths %d verified %s' % (
    st.median([r['gpu_ms'] or 0 for r in rs]), st.median([r['wall_ms'] for r in rs]),
    rs[-1]['launches'], rs[-1].get('submits'), rs[-1]['queue_growths'], all(r['verified'] for r in rs)))
PY
done
# 4. The scheduler's GPU tests on the H200.
timeout 240 $B/scheduler_gpu --test-threads 1 > $R/scheduler_gpu.log 2>&1; echo "scheduler_gpu rc=$?" >> $R/tests.txt
tail -3 $R/scheduler_gpu.log >> $R/tests.txt
md5sum $R/*.png > $R/md5.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/bench.txt $R/frames.txt $R/overflow.txt $R/tests.txt
