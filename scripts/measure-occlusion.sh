#!/usr/bin/env bash
# Issue 20, item 5 on one GPU (the device tool's `nvidia-h200`): pipelined frames (`reyes bench`)
# with and without occlusion culling from the previous frame (docs/reyes.md, *Occlusion
# culling*), per strategy, on the stacked scene (256 layers of 4x4 patches at 1920x1080, at a
# fixed angle: turned far its layers go edge-on and through the eye), its front layer alone,
# and Killeroo at 1920x1080 turning. Run from the repository root:
#
#   bash scripts/measure-occlusion.sh [REYES_BINARY] [STACKED_RIB_BINARY] [KILLEROO.rib]
#
# (release binaries: `cargo build --release -p reyes-cli && cargo build --release -p reyes
# --example stacked_rib`). Writes under ${OUT:-/tmp/occlusion-out}: each bench's JSON, the last
# frame's PNG with culling on and off (which must be the same bytes: cmp), and a summary line
# per bench (medians of the timed frames). The lead records the figures in docs/results.md.
set -euo pipefail
REYES="${1:-target/release/reyes}"
STACKED="${2:-target/release/examples/stacked_rib}"
KILLEROO="${3:-${REYES_SHARED_DATA:-../shared/data}/rib/killeroo.rib}"
# Sizes (the defaults are the issue's; small ones check the script on lavapipe).
FRAMES="${FRAMES:-50}" LAYERS="${LAYERS:-256}" W="${W:-1920}" H="${H:-1080}"
OUT="${OUT:-/tmp/occlusion-out}"
mkdir -p "$OUT"
[ -f scripts/device-setup.sh ] && source scripts/device-setup.sh
"$STACKED" "$LAYERS" 4 "$W" "$H" > "$OUT/stacked.rib"
"$STACKED" 1 4 "$W" "$H" > "$OUT/front.rib"
summary() {
    python3 -c "import json,sys; r=json.load(open(sys.argv[1])); g=r['gpu_ms']; print(sys.argv[2], r['strategy'], 'occlusion', r['occlusion'], 'GPU', g and round(g['median'],3), 'wall', round(r['wall_ms']['median'],3), 'mp', r['micropolygons']['median'], 'occluded', r['occluded']['median'], 'rerendered', r['rerendered'], 'of', r['frames'])" "$1" "$2"
}
for s in megakernel multipass multipass-host; do
    for o in on off; do
        "$REYES" bench "$OUT/stacked.rib" --strategy "$s" --occlusion "$o" --frames "$FRAMES" \
            --json -o "$OUT/stacked-$s-$o.png" > "$OUT/stacked-$s-$o.json"
        summary "$OUT/stacked-$s-$o.json" "stacked-$LAYERS"
        "$REYES" bench "$KILLEROO" --width "$W" --height "$H" --turntable --strategy "$s" \
            --occlusion "$o" --frames "$FRAMES" --json -o "$OUT/killeroo-$s-$o.png" \
            > "$OUT/killeroo-$s-$o.json"
        summary "$OUT/killeroo-$s-$o.json" "killeroo-${W}x$H"
    done
    "$REYES" bench "$OUT/front.rib" --strategy "$s" --occlusion off --frames "$FRAMES" --json \
        > "$OUT/front-$s.json"
    summary "$OUT/front-$s.json" "front-layer-alone"
    cmp "$OUT/stacked-$s-on.png" "$OUT/stacked-$s-off.png" && echo "stacked $s: same image"
    cmp "$OUT/killeroo-$s-on.png" "$OUT/killeroo-$s-off.png" && echo "killeroo $s: same image"
done
