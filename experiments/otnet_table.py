#!/usr/bin/env python3
"""results/otnet.md from the files experiments/otnet.sh writes into results/."""
import json
import os
import sys

res = sys.argv[1] if len(sys.argv) > 1 else "results"


def load(name):
    path = os.path.join(res, name)
    return json.load(open(path)) if os.path.exists(path) else None


def f(v, nd=2):
    return "-" if v is None else f"{v:.{nd}f}"


e = load("otnet_eval.json")
b = load("otnet_bench.json")
out = ["# OTNet on Occ-Traj120 (thesis ch 6)", "",
       "Regenerate: `experiments/otnet.sh` (configs/otnet/occ_traj120.yaml; one seed; the settings "
       "chosen on the validation maps by the lowest validation Frechet MTD, see otnet_sweep.md). Maps are "
       "split by map 70/10/20 (seed 0); figures are on the test maps, in grid cells. MTD: for each "
       "generated trajectory the distance to the nearest ground-truth trajectory of the map "
       "(Hausdorff: max of the two one-sided distances; Frechet: discrete, Eiter-Mannila), all "
       "resampled to 100 points at uniform normalised time; mean over generated trajectories, then "
       "over maps. Coverage: the reverse (each ground truth to the nearest generated one). ANLL: "
       "mean over ground-truth trajectories and 100 uniform tau of -log p_tau(xi(tau)), p_tau the "
       "predicted 2-D density at tau (OTNet: the mixture's exact marginals; k-NN and the mean "
       "trajectory: a Gaussian per tau fitted to their trajectories, variance floor "
       "0.05 cells^2). OTNet generates 100 collision-free trajectories per map (samples crossing "
       "an occupied cell are rejected and counted); k-NN transfers all trajectories of the nearest "
       "training map by the averaged Hausdorff distance (k = 1, as the thesis).", ""]
if e:
    out += [f"Test maps: {int(e['maps'])}, ground-truth trajectories: {int(e['trajectories'])}.", "",
            "| method | Hausdorff MTD | Frechet MTD | ANLL | coverage (Hausdorff) |",
            "|---|---|---|---|---|",
            f"| OTNet (ours) | {f(e['hausdorff'])} | {f(e['frechet'])} | {f(e['anll'])} | "
            f"{f(e['coverage_hausdorff'])} |",
            f"| k-NN (k = 1) | {f(e['knn_hausdorff'])} | {f(e['knn_frechet'])} | {f(e['knn_anll'])} | "
            f"{f(e['knn_coverage_hausdorff'])} |",
            f"| mean trajectory | {f(e['mean_hausdorff'])} | {f(e['mean_frechet'])} | "
            f"{f(e['mean_anll'])} | {f(e['mean_coverage_hausdorff'])} |",
            f"| control: OTNet's samples, one Gaussian per tau | - | - | {f(e.get('samples_anll'))} | - |",
            "| thesis OTNet (authors' test maps) | 1.98 | 2.13 | 29.83 | - |",
            "| thesis k-NN | 2.03 | 2.14 | 31.46 | - |", "",
            f"OTNet samples accepted (collision-free): {f(100 * e['acceptance_rate'], 1)} %; maps "
            f"without any valid sample: {int(e['maps_without_valid_samples'])}.", ""]
    if "cond_hausdorff" in e:
        out += ["Conditioned on each test map's mean ground-truth start (OTNet: all components, "
                "reweighted by the start's likelihood; k-NN: its trajectories translated to start "
                "there):", "",
                "| method | Hausdorff MTD | Frechet MTD |", "|---|---|---|",
                f"| OTNet, start-conditioned | {f(e['cond_hausdorff'])} | {f(e['cond_frechet'])} |",
                f"| k-NN, translated | {f(e['knn_cond_hausdorff'])} | {f(e['knn_cond_frechet'])} |",
                ""]
    out += ["The ANLL's absolute level depends on its definition (the thesis does not print "
            "one); compare rows of this table, not with the thesis's 29.83.", "",
            "Pictures: otnet_test_maps.png (test maps: OTNet, k-NN, start-conditioned OTNet; "
            "ground truth in blue), otnet_transfer.png (sections of the Intel-lab Hilbert map; samples that fail the collision check drawn orange).", ""]
if b:
    out += ["## Engine benchmark (`foresight bench runs/otnet_chosen "
            "--json`, one core, medians)", "",
            "| step | us |", "|---|---|",
            f"| encode a new map (database {b.get('database_size')}) | {f(b.get('encode_us'), 1)} |",
            f"| network, engine | {f(b.get('network_engine_us'), 1)} |",
            f"| network, LibTorch | {f(b.get('network_libtorch_us'), 1)} |",
            f"| condition + 100 collision-checked trajectories | {f(b.get('generate_us'), 1)} |",
            f"| total | {f(b.get('total_us'), 1)} |", "",
            f"LibTorch / engine on the network: {f(b.get('libtorch_over_engine'), 1)}x. Target: "
            "total <= 2000 us.", ""]
print("\n".join(out))
