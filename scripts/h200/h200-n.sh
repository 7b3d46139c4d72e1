# Session 18, fourth run: idle workgroups pausing between polls (EXP_BACKOFF = the longest
# pause in loop trips, doubling per idle turn; 0 = none) and the launch width, on a chain
# (one turn's latency), the binary and deep trees.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
S=$B/schedbench-exp
q() { python3 -c "
import json,sys
rs=[json.loads(l) for l in open(sys.argv[1]) if l.startswith('{')]
g=sorted(x['gpu_ms'] for x in rs if x.get('gpu_ms') is not None); ok=all(x['verified'] for x in rs)
print('%-34s %.3f %s idle %s wg %s' % (sys.argv[2], g[len(g)//2], '' if ok else 'UNVERIFIED', rs[-1]['idle_polls'], rs[-1]['workgroups']))
" $1 $2; }
for wg in 0 528 264; do W=""; [ $wg != 0 ] && W="--workgroups $wg"
 for bo in 0 64 512 4096; do
  for t in chain binary deep irregular; do
    case $t in chain) A="--roots 1 --fanout fixed:1 --depth 2000";; *) A="--preset $t";; esac
    n=$t-wg$wg-bo$bo
    EXP_BACKOFF=$bo timeout 60 $S --workload tree $A --strategy megakernel $W --runs 7 --json > $R/$n.jsonl 2> $R/$n.log
    q $R/$n.jsonl $n >> $R/table.txt
  done
 done
done
tar czf $OUT/results.tgz -C $OUT r
cat $R/table.txt
