#!/usr/bin/env python3
"""Criterion table and scaling slopes from the last `cargo bench -p satsim-tree --bench algorithms`.

Reads target/criterion/<model>/<algorithm>/<dof>/new/estimates.json (criterion's mean, or
its slope estimate when it has one) and prints a markdown table of ns per call, then the
log-log slopes of time against the number of bodies, d log t / d log n, for chains and
binary trees between 10 and 100 bodies, 100 and 1000 bodies, and 10 and 1000 bodies.

Usage: python3 benches/slopes.py [CRITERION_DIR]
"""
import json
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CRIT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "criterion")
ALGS = ("crba", "rnea", "aba", "crba_cholesky")
MODELS = ["satellite"] + [f"{k}{n}" for n in (10, 100, 1000) for k in ("chain", "binary")]


def estimate(model, alg):
    d = os.path.join(CRIT, model, alg)
    if not os.path.isdir(d):
        return None, None
    (dof,) = os.listdir(d) if len(os.listdir(d)) == 1 else [x for x in os.listdir(d) if x.isdigit()]
    with open(os.path.join(d, dof, "new", "estimates.json")) as f:
        e = json.load(f)
    return int(dof), (e.get("slope") or e["mean"])["point_estimate"]


def fmt(ns):
    return f"{ns:.0f} ns" if ns < 1e3 else f"{ns / 1e3:.2f} µs" if ns < 1e6 else f"{ns / 1e6:.2f} ms"


t = {}
print("| model | bodies | DOF | " + " | ".join(ALGS) + " |")
print("|---|---:|---:|" + "---:|" * len(ALGS))
for m in MODELS:
    row = []
    dof = None
    for a in ALGS:
        dof, ns = estimate(m, a)
        t[m, a] = ns
        row.append(fmt(ns) if ns else "-")
    bodies = 6 if m == "satellite" else int(m.lstrip("chainbry"))
    print(f"| {m} | {bodies} | {dof} | " + " | ".join(row) + " |")

print("\n| tree | algorithm | slope 10→100 | slope 100→1000 | slope 10→1000 |")
print("|---|---|---:|---:|---:|")
for k in ("chain", "binary"):
    for a in ALGS:
        s = [math.log(t[f"{k}{b}", a] / t[f"{k}{c}", a]) / math.log(b / c)
             for c, b in ((10, 100), (100, 1000), (10, 1000))]
        print(f"| {k} | {a} | " + " | ".join(f"{x:.2f}" for x in s) + " |")
