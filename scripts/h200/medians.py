#!/usr/bin/env python3
"""One line per strategy of a `schedbench --json` file: the median GPU ms (wall ms for the CPU)
and whether every run was verified. Usage: medians.py RUNS.jsonl LABEL"""
import json
import sys

runs = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
by = {}
for r in runs:
    by.setdefault(r["strategy"], []).append(r)
out = []
for strategy, rs in by.items():
    ms = sorted(x["gpu_ms"] if x.get("gpu_ms") is not None else x["wall_ms"] for x in rs)
    ok = all(x["verified"] for x in rs)
    out.append("%s %.3f%s" % (strategy, ms[len(ms) // 2], "" if ok else " UNVERIFIED"))
print("%-34s" % sys.argv[2], " | ".join(out))
