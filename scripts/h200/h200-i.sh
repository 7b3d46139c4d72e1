# Session 17, second run: the capacity-16 overflow after capping the multi-pass's anticipation
# (growth::Anticipation::MAX_FACTOR, MAX_EXTRA_BYTES), every strategy, 5 runs each.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
for cap in "" "--capacity 16"; do
  timeout 200 $B/schedbench --workload tree --strategy all --runs 5 --seed 32 --depth 15 --fanout uniform:4 --roots 45 --workgroups 485 $cap --json > $R/overflow${cap:+-16}.jsonl 2> $R/overflow${cap:+-16}.log
  python3 - $R/overflow${cap:+-16}.jsonl "cap${cap:+16}" >> $R/overflow.txt <<'PY'
import json, sys, statistics as st
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith('{')]
by = {}
for r in rows: by.setdefault(r['strategy'], []).append(r)
for s, rs in by.items():
  print(sys.argv[2], s, 'gpu %.3f wall %.3f launches %d growths %d bytes %d verified %s' % (
    st.median([r['gpu_ms'] or 0 for r in rs]), st.median([r['wall_ms'] for r in rs]),
    rs[-1]['launches'], rs[-1]['queue_growths'], rs[-1]['queue_bytes'], all(r['verified'] for r in rs)))
PY
done
tar czf $OUT/results.tgz -C $OUT r
cat $R/overflow.txt
