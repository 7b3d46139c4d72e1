# Session 19: planar (structure-of-arrays) items against interleaved ones in the host-driven
# multi-pass, on trees of 4-, 16- and 64-word items (payload 2, 14, 62), alternated A B A B.
source .devbin/setup.sh
R=$OUT/s; mkdir -p $R
for pay in 1 2 14 62; do for rep in 1 2; do for l in interleaved planar; do
  n=p$pay-$l-$rep
  timeout 100 $B/schedbench --workload tree --payload $pay --strategy multipass-host --item-layout $l --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
  python3 scripts/h200/medians.py $R/$n.jsonl $n >> $R/table.txt
done; done; done
cat $R/table.txt
