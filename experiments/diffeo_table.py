#!/usr/bin/env python3
"""results/diffeo.md from the eval.json files experiments/diffeo.sh copies into results/."""
import json
import statistics
import os
import sys

res = sys.argv[1] if len(sys.argv) > 1 else "results"


def load(name):
    path = os.path.join(res, name)
    return json.load(open(path)) if os.path.exists(path) else None


def f(v, nd=3):
    return "-" if v is None else f"{v:.{nd}f}"


lasa = load("diffeo_lasa.json")
push = load("diffeo_jaco_push_box.json")
lift = load("diffeo_jaco_lift_box.json")
bench = load("diffeo_bench.json")
out = ["# Diffeomorphic templates (thesis ch 8)", "",
       "Regenerate: `experiments/diffeo.sh` (configs/diffeo/lasa.yaml, jaco_push_box.yaml, "
       "jaco_lift_box.yaml; one seed). LASA figures are in normalised units (every shape scaled "
       "into [-0.5, 0.5], goal at the origin, the same normalisation for both methods); JACO "
       "figures in metres. F.D.: discrete Frechet distance between a rollout from a "
       "demonstration's start and that demonstration, both resampled to 100 points by arc length, "
       "mean over demonstrations; M.C.D.: maximum collision depth over all rollouts (the arm's "
       "body balls for JACO). The obstacle-flow time and the EFlow repulsor gain are selected on "
       "the fitted occupancy map from the training demonstrations' starts (LASA: and, of those "
       "that clear them, the first with the fewest rollouts from the stability grid's starts "
       "crossing the map), never on the exact obstacle the M.C.D. uses nor from a test start.", ""]
if lasa:
    m, shapes = lasa["mean"], lasa["shapes"]
    n = lasa["shape_count"]
    if n < 24:
        out += [f"**Partial**: {n} shapes ({', '.join(sorted(shapes))}). A stopped run is finished by "
                "`RESUME=1 experiments/diffeo.sh`; these figures came from `foresight eval "
                "runs/diffeo_lasa \"data.shapes=[...]\"` over the trained shapes.", ""]
    out += [f"## LASA, {n} shapes: imitation (5 of 7 demos trained on)", "",
            "| method | F.D. all starts | F.D. held-out starts | reach rate (demo starts) | reach rate (grid of starts) |",
            "|---|---|---|---|---|",
            f"| ours (RBF flow) | {f(m.get('frechet'))} | {f(m.get('frechet_heldout'))} | {f(m.get('reach_rate'))} | {f(m.get('grid_reach_rate'))} |",
            f"| Euclideanizing Flows | {f(m.get('eflow_frechet'))} | {f(m.get('eflow_frechet_heldout'))} | {f(m.get('eflow_reach_rate'))} | {f(m.get('eflow_grid_reach_rate'))} |",
            ""]
    if m.get("eflow_frechet"):
        out += [f"Ours / EFlow mean F.D.: {m['frechet'] / m['eflow_frechet']:.3f} "
                "(target: <= 1.10). Shapes whose grid of starts all reach the goal: ours "
                f"{sum(1 for s in shapes.values() if s.get('grid_reach_rate') == 1)}/{n}, EFlow "
                f"{sum(1 for s in shapes.values() if s.get('eflow_grid_reach_rate') == 1)}/{n}.", ""]
    out += [f"## LASA, {n} shapes: an obstacle half-way along the demonstrations", "",
            "| method | mean F.D. | mean M.C.D. | max M.C.D. | shapes with M.C.D. = 0 | reach rate |",
            "|---|---|---|---|---|---|"]
    for label, p in [("ours, with avoidance", "avoid_"), ("ours, no avoidance", ""),
                     ("EFlow", "eflow_"), ("EFlow + repulsor", "eflow_repulsor_"),
                     ("linear", "linear_")]:
        key = p + "mcd"
        if key not in m:
            continue
        zero = sum(1 for s in shapes.values() if s.get(key, 1) == 0)
        mx = max(s.get(key, 0) for s in shapes.values())
        out.append(f"| {label} | {f(m.get(p + 'frechet'))} | {f(m.get(key), 4)} | {f(mx, 4)} | {zero}/{n} | {f(m.get(p + 'reach_rate'))} |")
    out += ["", "Per shape (F.D. ours / EFlow; with the obstacle: F.D. and M.C.D. of ours with "
            "avoidance and of EFlow + repulsor; obstacle-flow time selected; grid crossings: rollouts "
            "from the stability grid's free starts that cross the map at the selected setting, ours / "
            "EFlow + repulsor, docs/diffeo.md \"Selection\"; step: one composed rollout step with the "
            "selected obstacle flow, on the points its rollouts pass, one thread, median of 3 passes; "
            "with a tabulated obstacle map (obstacle.map_table_spacing), the same flow on the exact map "
            "in the same run beside it):", "",
            "| shape | F.D. ours | F.D. EFlow | grid reach | avoid F.D. | avoid M.C.D. | EFlow+rep F.D. | EFlow+rep M.C.D. | flow time (Euler steps) | grid crossings | step (us) | step, exact map (us) |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, s in sorted(shapes.items()):
        out.append(f"| {name} | {f(s.get('frechet'))} | {f(s.get('eflow_frechet'))} | {f(s.get('grid_reach_rate'), 2)} | "
                   f"{f(s.get('avoid_frechet'))} | {f(s.get('avoid_mcd'), 4)} | {f(s.get('eflow_repulsor_frechet'))} | "
                   f"{f(s.get('eflow_repulsor_mcd'), 4)} | {f(s.get('obstacle_flow_time'), 4)} ({f(s.get('obstacle_flow_steps'), 0)}) | "
                   f"{f(s.get('obstacle_grid_crossing'), 0)} / {f(s.get('eflow_repulsor_grid_crossing'), 0)} | "
                   f"{f(s.get('avoid_step_us'), 1)} | {f(s.get('avoid_step_us_exact_map'), 1)} |")
    steps_us = sorted(s["avoid_step_us"] for s in shapes.values() if "avoid_step_us" in s)
    if steps_us:
        out += ["", f"One composed 2-D step with the selected obstacle flow: median {statistics.median(steps_us):.1f} us, "
                f"range {steps_us[0]:.1f}-{steps_us[-1]:.1f} us over {len(steps_us)} shapes; "
                f"{sum(1 for v in steps_us if v <= 20)} of {len(steps_us)} within the 20 us target."]
    exact_us = sorted(s["avoid_step_us_exact_map"] for s in shapes.values() if "avoid_step_us_exact_map" in s)
    errors = sorted(s["table_velocity_error"] for s in shapes.values() if "table_velocity_error" in s)
    if exact_us:
        out += ["", f"The same flows on the exact map (feature sums) in the same run: median {statistics.median(exact_us):.1f} us, "
                f"range {exact_us[0]:.1f}-{exact_us[-1]:.1f} us; {sum(1 for v in exact_us if v <= 20)} of {len(exact_us)} within 20 us. "
                f"Largest difference of the composed velocity, table vs exact map, over the points timed, relative to the "
                f"largest velocity there: median {statistics.median(errors):.1e}, at most {errors[-1]:.1e}."]
    out.append("")
thesis = {"ours, with avoidance": ("0.124 / 0", "0.127 / 0"), "ours, no avoidance": ("0.070 / 0.012", "0.112 / 0.012"),
          "EFlow": ("0.068 / 0.012", "0.093 / 0.152"), "EFlow + repulsor": ("0.168 / 0", "0.252 / 0.001"),
          "linear": ("0.242 / 0.147", "0.205 / 0.031")}
if push or lift:
    out += ["## JACO arm in C-space: push box, lift box (F.D. / M.C.D. in metres / reach rate)", "",
            "Task-space demonstrations are generated (the thesis's recordings are not public: "
            "datasets/synthetic_demos.h), so the thesis columns (F.D. / M.C.D.) are not the same data. "
            "Reach rate: share of rollouts from the demos' starts whose end effector reaches the goal.",
            "", "| method | push box | lift box | thesis push box | thesis lift box |", "|---|---|---|---|---|"]
    for label, p in [("ours, with avoidance", "avoid_"), ("ours, no avoidance", ""),
                     ("EFlow", "eflow_"), ("EFlow + repulsor", "eflow_repulsor_"), ("linear", "linear_")]:
        cells = []
        for r in (push, lift):
            s = r["mean"] if r else {}
            cells.append("-" if (p + "frechet") not in s else
                         f"{f(s.get(p + 'frechet'))} / {f(s.get(p + 'mcd'), 4)} / {f(s.get(p + 'reach_rate'), 2)}")
        out.append(f"| {label} | {cells[0]} | {cells[1]} | {thesis[label][0]} | {thesis[label][1]} |")
    for name, r in (("push box", push), ("lift box", lift)):
        if r and "obstacle_flow_time" in r["mean"]:
            s = r["mean"]
            out.append(f"\n{name}: obstacle-flow time {s['obstacle_flow_time']:g} "
                       f"({s.get('obstacle_flow_steps', 0):.0f} Euler steps), cleared on the map from the "
                       f"training starts: {'yes' if s.get('obstacle_cleared_on_map') else 'no'}; EFlow "
                       f"repulsor gain {s.get('eflow_repulsor_gain', 0):g}, cleared: "
                       f"{'yes' if s.get('eflow_repulsor_cleared_on_map') else 'no'}."
                       + (f" One composed C-space step with this obstacle flow, on the configurations "
                          f"its rollouts pass (one thread, median of 3 passes): "
                          f"{s['avoid_step_us']:.0f} us (target <= 100 us)."
                          if "avoid_step_us" in s else ""))
    out.append("")
if bench:
    arts = ", ".join(bench.get(p, {}).get("artifact", "-") for p in ("planar", "cspace"))
    out += ["## Time per rollout step (one core; `foresight bench ARTIFACT`)", "",
            f"Artifacts: {arts}. The composed 2-D step uses a 16-step obstacle flow and the C-space step "
            "a 10-step one; the evaluation's selected obstacle flows are longer (LASA: up to hundreds of "
            "steps; JACO: the Euler steps in the notes above), and the step time grows with them.", "",
            "| step | us |", "|---|---|"]
    for part, label in (("planar", "planar"), ("cspace", "JACO")):
        for k, v in bench.get(part, {}).get("steps_us", {}).items():
            out.append(f"| {label}: {k} | {f(v, 2)} |")
    out.append("")
print("\n".join(out))
