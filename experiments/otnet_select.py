#!/usr/bin/env python3
"""Chooses OTNet's hyper-parameters on the validation maps of the sweep in experiments/otnet.sh.

Criterion: the lowest validation Frechet MTD (the stricter of the two trajectory distances: it follows
the order of the points); only
val_* figures are read. Prints the chosen run's name (its overrides are in
<sweep>/<name>/overrides.txt), or (--table) a markdown table of the sweep's validation figures.
"""
import json
import os
import sys

sweep = sys.argv[1]
runs = {}
for name in sorted(os.listdir(sweep)):
    path = os.path.join(sweep, name, "eval.json")
    if os.path.exists(path):
        runs[name] = json.load(open(path))
if not runs:
    sys.exit(f"{sweep}: no finished run")
chosen = min(runs, key=lambda n: runs[n]["val_frechet"])


if "--table" in sys.argv:
    keys = ["val_hausdorff", "val_frechet", "val_anll", "val_knn_hausdorff", "val_knn_frechet",
            "val_knn_anll", "val_acceptance_rate"]
    print("# OTNet validation sweep (`experiments/otnet.sh`; chosen by the lowest val_frechet)\n")
    print("| run | overrides | " + " | ".join(keys) + " |")
    print("|---|---|" + "---|" * len(keys))
    for n, e in runs.items():
        mark = " (chosen)" if n == chosen else ""
        o = os.path.join(sweep, n, "overrides.txt")
        o = open(o).read().strip() if os.path.exists(o) else ""
        print(f"| {n}{mark} | `{o}` | " + " | ".join(f"{e.get(k, float('nan')):.3f}" for k in keys) + " |")
else:
    print(chosen)
