# Session 19: the full suite with the final schedbench (tree leaves folded per workgroup step,
# direct enqueue and planar items by the programs' rules), into docs/suite-h200.
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/y; mkdir -p $R
timeout 420 $B/schedbench --suite --size full --out $R/suite --runs 5 > $R/suite.log 2>&1
echo "suite rc=$?" >> $R/suite.log
tail -5 $R/suite.log
python3 -c "
import json
rs=[json.loads(l) for l in open('$R/suite/runs.jsonl')]
print(len(rs),'runs', sum(1 for r in rs if r['verified']),'verified')"
cd $OUT && tar czf y.tgz y && rm -rf y
