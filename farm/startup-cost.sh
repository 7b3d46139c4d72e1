#!/usr/bin/env bash
# What starting a process costs a farm task: renders N copies of a one-frame scene as one
# N-frame shot, (a) in one process (`reyes render --frames 1-N`, a chunk of N) and (b) in N
# processes (`reyes render --frame i` each, one frame per task), RUNS times each, and prints
# the median wall seconds per frame of both and the start-up per process they imply:
#   one process:  S + N F        N processes:  N (S + F)   =>   S = (b - a) / (N - 1)
# (S includes what each task spends reading the frames it does not render: every task reads
# the shot file to its end.)
#
#   farm/startup-cost.sh REYES SCENE N RUNS [reyes render options]
#   farm/startup-cost.sh target/release/reyes $REYES_SHARED_DATA/rib/killeroo.rib 3 3 --gpu
#
# SCENE: a RIB of one frame (a `FrameBegin 1` block, or none: the file is then wrapped in one).
# Prints one line per run and a summary line; writes its shot and images to a temporary folder.
set -euo pipefail
if [ $# -lt 4 ]; then
    echo "usage: $0 REYES SCENE N RUNS [reyes render options]" >&2
    exit 2
fi
reyes=$(realpath "$1")
scene=$2
n=$3
runs=$4
shift 4
[ "$n" -ge 2 ] || { echo "N must be 2 or more" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}

# The shot: N copies of the scene, frame i numbered i (a scene that reads maps or archives by
# relative paths would need them beside the temporary shot).
text=$(cat "$scene")
for i in $(seq "$n"); do
    if grep -q '^FrameBegin 1' <<<"$text"; then
        sed "s/^FrameBegin 1\$/FrameBegin $i/" <<<"$text"
    else
        printf 'FrameBegin %s\n%s\nFrameEnd\n' "$i" "$text"
    fi
done >"$tmp/shot.rib"

now() { date +%s.%N; }
calc() { awk "BEGIN { print $1 }"; }
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

one=()
many=()
for r in $(seq "$runs"); do
    rm -f "$tmp"/a.*.png "$tmp"/b.*.png
    t0=$(now)
    "$reyes" render "$tmp/shot.rib" --frames "1-$n" -o "$tmp/a.%04d.png" "$@" 2>"$tmp/a.log" ||
        { cat "$tmp/a.log" >&2; exit 1; }
    t1=$(now)
    for i in $(seq "$n"); do
        "$reyes" render "$tmp/shot.rib" --frame "$i" -o "$tmp/b.%04d.png" "$@" 2>"$tmp/b.log" ||
            { cat "$tmp/b.log" >&2; exit 1; }
    done
    t2=$(now)
    for i in $(seq "$n"); do
        f=$(printf '%04d' "$i")
        [ -f "$tmp/a.$f.png" ] && [ -f "$tmp/b.$f.png" ] || { echo "frame $i was not written" >&2; exit 1; }
    done
    a=$(calc "$t1 - $t0")
    b=$(calc "$t2 - $t1")
    one+=("$a")
    many+=("$b")
    printf 'run %d: one process %.2f s, %d processes %.2f s\n' "$r" "$a" "$n" "$b"
done
a=$(printf '%s\n' "${one[@]}" | median)
b=$(printf '%s\n' "${many[@]}" | median)
printf 'median of %d runs, %d frames: one process %.2f s (%.2f s/frame), one process per frame %.2f s (%.2f s/frame); start-up per process %.2f s, a frame %.2f s\n' \
    "$runs" "$n" "$a" "$(calc "$a / $n")" "$b" "$(calc "$b / $n")" \
    "$(calc "($b - $a) / ($n - 1)")" "$(calc "($a - ($b - $a) / ($n - 1)) / $n")"
