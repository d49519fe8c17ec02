#!/usr/bin/env python3
"""results/constrained.md from results/constrained_<dataset>.json (experiments/constrained.sh)."""
import json
import pathlib
import sys

root = pathlib.Path(sys.argv[1])
names = {"synthetic": "Synthetic scenes", "occ_traj": "Occ-Traj120 (simulated)",
         "thor": "THOR (indoors)", "eth": "ETH seq_eth + seq_hotel (outdoors)"}


def f(v, nd=2):
    return "-" if v is None else f"{v:.{nd}f}"


def pct(v):
    return "-" if v is None else f"{100 * v:.1f} %"


print("# Structurally constrained prediction (thesis ch 7)\n")
print("Regenerate: `experiments/constrained.sh` (then this table: "
      "`python3 experiments/constrained_table.py results > results/constrained.md`).")
print("ADE/FDE: mean of the component nearest to the truth (thesis); AL: average likelihood of the "
      "truth (density, higher is better); ANLL: mean -log density; C.V.P: share of test windows "
      "with C - 0.05 > 0. CV and the naive network are point predictions. Basis gamma chosen on "
      "the validation ANLL of the prior (`results/constrained_<dataset>_choice.txt`).\n")
print("| dataset | model | windows | ADE | FDE | ADE (mixture mean) | AL | ANLL | C.V.P |")
print("|---|---|---|---|---|---|---|---|---|")
solve_rows = []
for ds, title in names.items():
    p = root / f"constrained_{ds}.json"
    if not p.exists():
        continue
    e = json.loads(p.read_text())
    for key, label in [("prior", "prior (ours, unoptimised)"), ("optimised", "optimised (ours)"),
                       ("prior_on_violating", "prior, violating windows only"),
                       ("optimised_on_violating", "optimised, same windows"),
                       ("ktm", "KTM"), ("cv", "constant velocity"), ("naive", "naive NN")]:
        b = e.get(key)
        if not b:
            continue
        print(f"| {title} | {label} | {b['windows']} | {f(b['ade'])} | {f(b['fde'])} | "
              f"{f(b['ade_mixture_mean'])} | {f(b['al'], 3)} | {f(b['anll'])} | "
              f"{pct(b.get('cvp'))} |")
    s = e["solve"]
    q = e["quadrature_accuracy"]
    solve_rows.append(
        f"| {title} | {s['solve_time_ms']['count']} | {f(s['solve_time_ms']['median'], 1)} | "
        f"{f(s['solve_time_ms']['p99'], 1)} | {f(s['solve_time_ms']['max'], 1)} | {s['failures']} | "
        f"{q['order']} | {f(q['max_abs_error_vs_monte_carlo'], 4)} "
        f"(MC s.e. {f(q['max_monte_carlo_standard_error'], 4)}) | "
        f"{f(q['max_abs_error_vs_reference_order'], 5)} | "
        f"{f(q['max_abs_change_with_4x_time_points'], 4)} |")
print("\n## Solves (one core) and the accuracy of C\n")
print("| dataset | solves | median ms | p99 ms | max ms | failures | GH order | "
      "max abs error vs Monte Carlo | vs order 20 | change with 4x time points |")
print("|---|---|---|---|---|---|---|---|---|---|")
for r in solve_rows:
    print(r)
