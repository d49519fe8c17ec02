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
      "with C - 0.05 > 0 under the run's quadrature; C.V.P converged: the same under the converged "
      "quadrature (Gauss-Hermite order 32, 16 midpoints per step). CV and the naive network are "
      "point predictions. Basis gamma chosen on the validation ANLL of the prior "
      "(`results/constrained_<dataset>_choice.txt`).\n")
print("| dataset | model | windows | ADE | FDE | ADE (mixture mean) | AL | ANLL | C.V.P | "
      "C.V.P converged |")
print("|---|---|---|---|---|---|---|---|---|---|")
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
              f"{pct(b.get('cvp'))} | {pct(b.get('cvp_converged'))} |")
    s = e["solve"]
    q = e["quadrature_accuracy"]
    qo = e.get("quadrature_accuracy_optimised", {})
    t = e.get("truth", {})
    choice = e.get("quadrature_choice")
    chosen = "configured"
    if choice:
        chosen = (f"chosen ({'meets' if choice['met'] else 'misses'} {choice['accuracy']}: "
                  f"{f(choice['max_abs_error'], 4)})")
    check = s.get("check_order", 0)
    if check:
        check = f"{check} x {s.get('check_substeps', 1)}"
        if choice and "check" in choice:
            ch = choice["check"]
            check += (f", chosen on {ch['windows']} projected ({'meets' if ch['met'] else 'misses'}"
                      f": {f(ch['max_abs_error'], 4)})")
    solve_rows.append(
        f"| {title} | {s['solve_time_ms']['count']} | {f(s['solve_time_ms']['median'], 1)} | "
        f"{f(s['solve_time_ms']['p99'], 1)} | {f(s['solve_time_ms']['max'], 1)} | {s['failures']} | "
        f"{q['order']} x {s.get('substeps', 1)} {s.get('time_rule', 'right')}, {chosen} | "
        f"{check if check else '-'} ({s.get('windows_solved_again_after_check', '-')}) | "
        f"{f(q.get('max_abs_error_vs_continuous_monte_carlo'), 4)} "
        f"(s.e. {f(q.get('max_continuous_monte_carlo_standard_error'), 4)}) | "
        f"{f(q.get('max_abs_error_vs_converged'), 4)} | "
        f"{f(qo.get('max_abs_error_vs_converged'), 4)} | "
        f"{f(t.get('mean_cost'), 4)} / {pct(t.get('cvp'))} |")
print("\n## Solves (one core) and the accuracy of C\n")
print("Quadrature: Gauss-Hermite order x time points per step and their rule; check: the order "
      "every result is verified at (windows solved again with a lowered target). Errors of C: the "
      "largest over the first `eval.accuracy_windows` test priors against Monte Carlo in continuous "
      "time and against the converged quadrature, and over projected windows against the converged "
      "quadrature (the solver seeks out the error of the rule it is given). Truth: the time-averaged "
      "p(m=1|x) along the true futures (mean / share above 0.05).\n")
print("| dataset | solves | median ms | p99 ms | max ms | failures | quadrature | check | "
      "prior C error vs continuous MC | vs converged | projected C error vs converged | truth C |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in solve_rows:
    print(r)
