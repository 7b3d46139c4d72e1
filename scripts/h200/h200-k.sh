# Session 18, first run: the large-payload tree's item copies (issue 10). EXP_TREE selects the
# tree bodies of an experimental build: 0 = indexing the item parameter (naga spills the value
# array to a temporary at every dynamic index), var = one `var` copy of the item, unroll = var +
# payload loops unrolled in the source. Then the binary tree under batch steps and workgroups.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
S=$B/schedbench-exp
q() { python3 -c "
import json,sys
rs=[json.loads(l) for l in open(sys.argv[1]) if l.startswith('{')]
by={}
for r in rs: by.setdefault(r['strategy'],[]).append(r)
for k,v in by.items():
  g=sorted(x['gpu_ms'] for x in v if x.get('gpu_ms') is not None); ok=all(x['verified'] for x in v)
  b=v[-1]
  print('%-40s %-16s gpu %8.3f  ok %s  batches %s idle %s launches %s' % (sys.argv[2], k, g[len(g)//2] if g else -1, ok, b.get('batches'), b.get('idle_polls'), b.get('launches')))
" $1 $2; }
for v in 0 var unroll; do
  for p in large-payload binary; do
    n=tree-$p-$v
    EXP_TREE=$v EXP_P=$([ $p = binary ] && echo 1 || echo 62) timeout 200 $S --workload tree --preset $p --strategy all --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
    q $R/$n.jsonl $n >> $R/table.txt
  done
done
for bs in 1 2 4; do for wg in 0 264 528 1056; do
  n=binary-bs$bs-wg$wg; W=""; [ $wg != 0 ] && W="--workgroups $wg"
  EXP_TREE=var timeout 100 $S --workload tree --preset binary --strategy megakernel --batch-steps $bs $W --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
  q $R/$n.jsonl $n >> $R/table.txt
done; done
nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv >> $R/table.txt
tar czf $OUT/results.tgz -C $OUT r
cat $R/table.txt
