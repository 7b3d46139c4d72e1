# Session 19: the megakernel's planar copy-out, two ways: A (schedbench: planar outbox, copied
# plane by plane, four planes per trip) and B (schedbench-exp: interleaved outbox written by
# vec4, each thread moving an item into the planar slots); interleaved beside; A B I A B I.
# Then whether pipelined multi-pass frames (reyes bench) draw on the H200, old build and new.
source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
R=$OUT/u; mkdir -p $R
for p in large-payload binary deep irregular; do for rep in 1 2; do
  for v in A B I; do bin=schedbench; l=planar; [ $v = B ] && bin=schedbench-exp; [ $v = I ] && l=interleaved
    n=$p-$v-$rep
    timeout 60 $B/$bin --workload tree --preset $p --strategy megakernel --item-layout $l --runs 10 --json > $R/$n.jsonl 2> $R/$n.log
    python3 scripts/h200/medians.py $R/$n.jsonl $n >> $R/table.txt
  done; done; done
for bin in reyes-prev reyes; do for st in multipass megakernel; do n=$bin-$st
  timeout 60 $B/$bin bench teapot --width 640 --height 480 --strategy $st --frames 3 -o $R/$n-bench.png > $R/$n-bench.txt 2>&1
  timeout 60 $B/$bin render teapot --width 640 --height 480 --strategy $st -o $R/$n-render.png > $R/$n-render.txt 2>&1
  echo "$n bench: $(tail -2 $R/$n-bench.txt | tr '\n' ' ')" >> $R/rt.txt
done; done
(cd $R && md5sum *.png > md5.txt)
cat $R/table.txt $R/rt.txt $R/md5.txt
cd $OUT && tar czf u.tgz --exclude='*.png' u && rm -rf u
