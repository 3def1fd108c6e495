"""Unknown data association on MRCLAM dataset 6, each of its five robots, ids hidden.

Each robot's log runs with every filter three ways: `--association known` (the barcodes'
ids: the reference), `nn` and `jcbb`, the barcodes then used only to score (metrics.json
`association`). The SEIFs gate with the local marginal unless --gate says otherwise, the
EKF with its exact one. The table gives, per robot: the share of the observations a run
kept that it associated correctly, the share of all labelled observations (as the ceiling
counts them), the ceiling itself (the true map seen from the Vicon pose, by likelihood,
individually), the landmarks at the end (duplicates; the dataset has 15) and the aligned
trajectory error (ATE) beside known association's and dead reckoning's.

A second table sorts the wrong ones, from each run's associations.csv (every observation's
landmark at the end, merges followed, and its verdict). An observation in a landmark whose
label (the truth id most of its observations carry) is not its own pairs it with another
landmark: of its cluster (the true landmarks within --cluster metres of its own) or of
another. One whose label is its own but whose landmark is a duplicate (an older landmark
carries that label) is in a second copy. The "wrong" column is metrics.json's `wrong`.

Run:  PYTHONPATH=build/python /usr/bin/python3 scripts/figures/association_mrclam.py
      [--dataset ../shared/data/mrclam/MRCLAM_Dataset6] [--robots 1,2,3,4,5]
      [--filters ekf,seif:profile=consistent] [--gate local|conservative|exact] [--jobs 2]
      [--cluster 0.35] [--out out/association-mrclam]
"""
import argparse
import csv
import os
import sys

import seif
from association_study import metrics, run_all  # the sibling study's CLI helpers

METHODS = ["known", "nn", "jcbb"]


def wrong_kinds(run_dir, truth, cluster):
    """The run's wrong associations by kind, from its associations.csv: {"cluster": n, "other": n, "copy": n}."""
    kinds = {"cluster": 0, "other": 0, "copy": 0}
    with open(os.path.join(run_dir, "associations.csv"), newline="") as f:
        for row in csv.DictReader(f):
            if row["verdict"] == "duplicate":
                kinds["copy"] += 1
            elif row["verdict"] == "wrong":
                t, label = int(row["truth"]), int(row["label"]) if row["label"] else None
                near = label in truth and ((truth[label] - truth[t]) ** 2).sum() ** 0.5 <= cluster
                kinds["cluster" if near else "other"] += 1
    return kinds


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dataset", default="../shared/data/mrclam/MRCLAM_Dataset6")
    p.add_argument("--robots", default="1,2,3,4,5")
    p.add_argument("--filters", default="ekf,seif:profile=consistent")
    p.add_argument("--gate", default="local", choices=["local", "conservative", "exact"])
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--cluster", type=float, default=0.35,
                   help="[m] true landmarks this close to one another are one cluster (MRCLAM 6: 0.13-0.27 m apart)")
    p.add_argument("--out", default="out/association-mrclam")
    a = p.parse_args()
    if not os.path.isdir(a.dataset):
        sys.exit(f"association_mrclam.py: {a.dataset} is not a folder (the MRCLAM dataset, ../shared/data/README.md)")
    robots = [int(r) for r in a.robots.split(",")]
    filters = seif.split_filter_list(a.filters)  # as the CLI's --filters

    jobs = {}
    for f in filters:
        gate = "exact" if f.startswith("ekf") else a.gate
        for r in robots:
            for m in METHODS:
                out = os.path.join(a.out, f"robot{r}-{f.replace(':', '_').replace('=', '-')}-{m}")
                flags = [] if m == "known" else ["--gate-marginal", gate]
                jobs[(f, r, m)] = (out, ["run", "--dataset", a.dataset, "--robot", str(r), "--filter", f,
                                         "--association", m, *flags, "--out", out])
    run_all([j[1] for j in jobs.values()], a.jobs)

    print("| filter | association | robot | correct of kept | of all labelled | ceiling | landmarks (duplicates) "
          "| ATE [m] | known | dead reckoning |")
    print("|---|---|---:|---:|---:|---:|---|---:|---:|---:|")
    for f in filters:
        for m in METHODS[1:]:
            for r in robots:
                x = metrics(jobs[(f, r, m)][0])
                known = metrics(jobs[(f, r, "known")][0])
                s = x["association"]
                print(f"| {f} | {m} | {r} | {100 * s['correct_fraction']:.1f} % "
                      f"| {100 * s['ceiling']['run_correct_fraction']:.1f} % "
                      f"| {100 * s['ceiling']['individual_fraction']:.1f} % "
                      f"| {s['landmarks_final']} ({s['duplicate_landmarks']}) | {x['ate_rmse']:.3f} "
                      f"| {known['ate_rmse']:.3f} | {x['dead_reckoning_ate_rmse']:.3f} |")

    print()
    truth = seif.open_dataset(a.dataset).info.landmarks  # id -> surveyed position
    print("| filter | association | robot | wrong | in a landmark of its cluster | of another cluster | in a second copy of its own |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for f in filters:
        for m in METHODS[1:]:
            for r in robots:
                k = wrong_kinds(jobs[(f, r, m)][0], truth, a.cluster)
                n = sum(k.values())
                share = {key: f"{100 * v / n:.1f} %" if n else "-" for key, v in k.items()}
                print(f"| {f} | {m} | {r} | {n} | {share['cluster']} | {share['other']} | {share['copy']} |")


if __name__ == "__main__":
    main()
