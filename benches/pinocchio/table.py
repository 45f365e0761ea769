#!/usr/bin/env python3
"""Summarise benches/pinocchio/run.sh's results: median over rounds, satsim/Pinocchio ratio."""
import json
import statistics
import sys

ALGS = ("aba", "crba", "rnea", "crba_cholesky")
rows = []
for line in open(sys.argv[1]):
    try:
        rows.append(json.loads(line))
    except json.JSONDecodeError:  # a side that failed (e.g. out of memory): no figure
        pass
models = list(dict.fromkeys(r["model"] for r in rows))
print("| model | DOF | algorithm | satsim ns | Pinocchio ns | satsim / Pinocchio |")
print("|---|---:|---|---:|---:|---:|")
for m in models:
    got = {side: [r["result"] for r in rows if r["model"] == m and r["side"] == side]
           for side in ("satsim", "pinocchio")}
    dof = got["satsim"][0]["dof"]
    for a in ALGS:
        s = statistics.median(x["ns_per_call"][a] for x in got["satsim"])
        if not got["pinocchio"]:
            print(f"| {m} | {dof} | {a} | {s:.0f} | failed | - |")
            continue
        p = statistics.median(x["ns_per_call"][a] for x in got["pinocchio"])
        print(f"| {m} | {dof} | {a} | {s:.0f} | {p:.0f} | {s / p:.2f} |")
print(f"\n(median over {len(got['satsim'])} interleaved rounds of each side's median of 7 "
      f"repetitions; calls per repetition {got['satsim'][0]['calls']} for the last model)")
