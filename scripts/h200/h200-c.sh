source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
timeout 420 $B/schedbench --suite --size full --out $R/suite --runs 5 > $R/suite.log 2>&1
echo "suite rc=$?" >> $R/suite.log
tar czf $OUT/results.tgz -C $OUT r
tail -3 $R/suite.log; grep -c '"verified":false' $R/suite/runs.jsonl; grep '"verified":false' $R/suite/runs.jsonl | cut -c1-300
