# Session 18, seventh run: batch steps and launch width for the large-payload tree (one
# 256-thread workgroup fits per SM once the payload lives in registers).
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
for bs in 1 2 4; do for wg in 0 132 264; do W=""; [ $wg != 0 ] && W="--workgroups $wg"
  n=lp-bs$bs-wg$wg
  timeout 60 $B/schedbench-exp --workload tree --preset large-payload --strategy megakernel --batch-steps $bs $W --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
  python3 -c "
import json,sys
rs=[json.loads(l) for l in open(sys.argv[1]) if l.startswith('{')]
g=sorted(x['gpu_ms'] for x in rs); print('%-20s %.3f %s wg %s idle %s' % (sys.argv[2], g[len(g)//2], all(x['verified'] for x in rs), rs[-1]['workgroups'], rs[-1]['idle_polls']))" $R/$n.jsonl $n >> $R/table.txt
done; done
cat $R/table.txt
