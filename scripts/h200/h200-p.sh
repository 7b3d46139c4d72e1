# Session 18, sixth run: issue 14 item 4 in Sattler & Steinberger's form. Killeroo at 800x600,
# megakernel: motion blur (--spin 30: 30 degrees about its z axis over the shutter) and depth of
# field (--dof 2.8,50,454: focused at the camera's distance to the model's centre), each
# algorithm at 16/25/64 samples per pixel (--samples 4/5/8), Interleave UVT with tiles 2, 3, 4;
# the same with zero motion (--spin 0); the image error of each against a 256-sample bbox
# reference (--samples 16). Then the cost of displacement (killeroo.rib with its
# `disp_textured` shaders, which reyes ignores, replaced by the built-in "bumps") and of exact
# normals.
source .devbin/setup.sh
R=$OUT/r; mkdir -p $R
K=$B/data/rib/killeroo.rib
KD=$R/killeroo-bumps.rib
sed 's/Displacement "disp_textured"/Displacement "bumps" "frequency" 4/' $K > $KD
row() { python3 -c "
import json,sys
d=json.load(open(sys.argv[1])); e=d.get('image_error') or {}
p=e.get('psnr_db'); f=e.get('flip_mean')
print('%-34s gpu %8.3f  wall %8.3f  psnr %s  flip %s' % (sys.argv[2], d['runs']['gpu_ms']['median'], d['runs']['wall_ms']['median'],
  'inf' if p is None and e else ('%.2f' % p if p is not None else '-'), '%.4f' % f if f is not None else '-'))
" $1 $2 2>&1 | tail -1; }
G="--width 800 --height 600 --strategy megakernel"
for effect in motion dof still; do
  case $effect in motion) E="--spin 30";; dof) E="--dof 2.8,50,454";; still) E="--spin 0";; esac
  timeout 200 $B/reyes render $K $G $E --sampling bbox --samples 16 --exr $R/ref-$effect.exr -o $R/ref-$effect.png > $R/ref-$effect.log 2>&1
  for s in 4 5 8; do
    for a in simple interleave:2 interleave:3 interleave:4 bbox; do
      alg=${a%%:*}; T=""; [ $alg = interleave ] && T="--il-tile ${a#*:}"
      n=$effect-${a/:/}-$s
      timeout 120 $B/reyes render $K $G $E --sampling $alg $T --samples $s --runs 10 --compare-to $R/ref-$effect.exr -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
      row $R/$n.json "$n" >> $R/table.txt
    done
  done
done
for s in 4 5 8; do n=plain-$s
  timeout 120 $B/reyes render $K $G --samples $s --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
  row $R/$n.json $n >> $R/table.txt
done
for rep in 1 2; do
  for v in plain bumps-exact bumps-approximate; do n=disp-$v-$rep
    case $v in plain) S=$K; N="";; bumps-exact) S=$KD; N="--displacement-normals exact";; *) S=$KD; N="--displacement-normals approximate";; esac
    timeout 120 $B/reyes render $S --width 1920 --height 1080 --strategy megakernel $N --runs 10 -o $R/$n.png --stats $R/$n.json > $R/$n.log 2>&1
    row $R/$n.json $n >> $R/table.txt
  done
done
tar czf $OUT/results.tgz -C $OUT r
cat $R/table.txt
