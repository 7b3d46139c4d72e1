# Part B: tree presets, the full suite, Killeroo accuracy before/after, 200,000 patches.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
K=$B/data/rib/killeroo.rib
for p in binary irregular deep large-payload heavy-work; do
  echo "== preset $p" >> $R/trees.txt
  timeout 200 $B/schedbench --workload tree --preset $p --strategy all --runs 10 >> $R/trees.txt 2>&1
  timeout 200 $B/schedbench --workload tree --preset $p --strategy megakernel --policy fifo --runs 10 2>&1 | grep -A3 "^strategy" >> $R/trees.txt
done
for w in mandelbrot bfs; do timeout 200 $B/schedbench --workload $w --strategy all --runs 10 > $R/$w.txt 2>&1; done
python3 $B/many-patches.gen.py $R/../many.rib
for st in megakernel multipass multipass-host; do
  /usr/bin/time -f "%e s" timeout 120 $B/reyes render $R/../many.rib --strategy $st -o $R/many-$st.png --stats $R/many-$st.json > $R/many-$st.log 2>&1
done
rm -f $R/../many.rib
for b in reyes-base reyes; do
  timeout 200 $B/$b measure $K --strategy megakernel --json > $R/measure-killeroo-$b.json 2> $R/measure-killeroo-$b.log
done
timeout 360 $B/schedbench --suite --size full --out $R/suite --runs 5 > $R/suite.log 2>&1
echo "suite rc=$?" >> $R/suite.log
tar czf $OUT/results.tgz -C $OUT r
cat $R/trees.txt | grep -v "^ratio" | head -70; tail -3 $R/many-*.log; grep -h psnr $R/measure-*.json | head; tail -3 $R/suite.log
