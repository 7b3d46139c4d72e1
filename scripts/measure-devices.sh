#!/usr/bin/env bash
# Issue 25 on a 2-GPU host (the device tool's `nvidia-h200-x2`): the multi-device renderer
# against one GPU, from one release binary. Run from the repository root:
#
#   bash scripts/measure-devices.sh [REYES_BINARY] [KILLEROO.rib]
#
# Writes its outputs under ${OUT:-/tmp/devices-out}: the bench JSON of one and two GPUs, the
# 7680x4320 frame on one and on both GPUs (PNG, --stats JSON) and their md5 sums. The lead
# records the figures in docs/results.md and docs/farm.md.
set -euo pipefail
REYES="${1:-target/release/reyes}"
KILLEROO="${2:-${REYES_SHARED_DATA:-../shared/data}/rib/killeroo.rib}"
OUT="${OUT:-/tmp/devices-out}"
mkdir -p "$OUT"
[ -f scripts/device-setup.sh ] && source scripts/device-setup.sh
"$REYES" devices | tee "$OUT/devices.txt"
# 1-2. Sixteen Killeroo frames at 1920x1080, one turn: one GPU, then both.
for d in 0 all; do
    "$REYES" bench "$KILLEROO" --turntable --frames 16 --warmup 4 --width 1920 --height 1080 \
        --devices "$d" --json > "$OUT/bench-$d.json"
    python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(sys.argv[2], 'fps', round(r['fps'],2), [(d['device'], d['frames'], round(d['fps'],2)) for d in r['devices']])" \
        "$OUT/bench-$d.json" "$d"
done
# 3. One 7680x4320 Killeroo frame: one GPU, then split over both (5 timed runs each).
for d in 0 all; do
    "$REYES" render "$KILLEROO" --width 7680 --height 4320 --devices "$d" --runs 5 \
        -o "$OUT/k8k-$d.png" --stats "$OUT/k8k-$d.json" 2>&1 | tail -4
done
md5sum "$OUT"/k8k-*.png
python3 - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
for d in ("0", "all"):
    s = json.load(open(f"{out}/k8k-{d}.json"))
    r = s["runs"]
    print(d, "wall median", r["wall_ms"]["median"], "GPU median", (r["gpu_ms"] or {}).get("median"),
          [(x["device"], x["buckets"], x["gpu_ms"], x["wall_ms"]) for x in s["devices"]])
PY
