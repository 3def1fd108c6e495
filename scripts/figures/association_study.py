"""Unknown data association on simulated worlds with clutter, against known association.

Each world (park, uniform-200) is simulated for seeds 1-5 with one false detection per scan
(Poisson) and 10 % missed detections. Every filter then runs on the same log three ways:
`--association known --drop-unlabelled` (the reference: the data's ids, clutter dropped),
`nn` and `jcbb`, with provisional landmarks in the filter and held outside it. The table
gives the share of observations associated correctly (mean, worst seed), the landmarks at
the end (spurious and duplicates summed over the seeds), the aligned map RMSE and its ratio
to the same filter's with known association on the same logs. "Correct" is over the
observations a run kept; "of all labelled" over every observation with a truth id, as the
ceiling counts. A second table gives each world's ceiling: the share the true map seen from the
true pose associates right by likelihood (eval/association_ceiling.hpp; metrics.json
association.ceiling).

The SEIFs gate with the local marginal unless --gate says otherwise (conservative needs
`bounds=true` in their specs); the EKF always with its exact one.

Run:  PYTHONPATH=build/python /usr/bin/python3 scripts/figures/association_study.py [--worlds park,uniform] [--seeds 5]
      [--filters ekf,seif,seif:profile=consistent] [--gate local|conservative|exact]
      [--provisional filter,held] [--jobs 2] [--out out/association-study]
"""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

import seif

SEIF = os.environ.get("SEIF", "build/bin/seif")
WORLDS = {"park": ["--preset", "park"], "uniform": ["--preset", "uniform", "--landmarks", "200"]}


def run(args):
    subprocess.run([SEIF, *args], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def run_all(arglists, workers):
    """run() of each argument list, `workers` at a time, with a count of the runs done."""
    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        for done, _ in enumerate(pool.map(run, arglists), 1):
            print(f"\r{done}/{len(arglists)} runs", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)


def metrics(folder):
    with open(os.path.join(folder, "metrics.json")) as f:
        return json.load(f)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--worlds", default="park,uniform")
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument("--filters", default="ekf,seif,seif:profile=consistent")
    p.add_argument("--gate", default="local", choices=["local", "conservative", "exact"])
    p.add_argument("--provisional", default="filter,held")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--out", default="out/association-study")
    a = p.parse_args()
    worlds = a.worlds.split(",")
    filters = seif.split_filter_list(a.filters)  # as the CLI's --filters
    seeds = range(1, a.seeds + 1)

    data = {(w, s): os.path.join(a.out, f"{w}-{s}") for w in worlds for s in seeds}
    run_all([["simulate", *WORLDS[w], "--seed", str(s), "--clutter", "1", "--detection-probability", "0.9",
              "--out", d] for (w, s), d in data.items()], a.jobs)

    cases = [("known", "filter")] + [(m, pl) for m in ("nn", "jcbb") for pl in a.provisional.split(",")]
    jobs = {}
    for (w, s), d in data.items():
        for f in filters:
            gate = "exact" if f.startswith("ekf") else a.gate
            for m, pl in cases:
                out = os.path.join(a.out, "runs", f"{w}-{s}-{f.replace(':', '_').replace('=', '-')}-{m}-{pl}")
                flags = ["--drop-unlabelled"] if m == "known" else ["--gate-marginal", gate, "--provisional", pl]
                jobs[(w, s, f, m, pl)] = (out, ["run", "--dataset", d, "--filter", f, "--association", m, *flags,
                                                "--out", out])
    run_all([j[1] for j in jobs.values()], a.jobs)

    print("| world | filter | gate | association | provisional | correct (worst seed) | of all labelled "
          "| landmarks (spurious, duplicates) | map RMSE [m] | known | ratio | s associating |")
    print("|---|---|---|---|---|---:|---:|---|---:|---:|---:|---:|")
    for w in worlds:
        for f in filters:
            known = [metrics(jobs[(w, s, f, "known", "filter")][0])["landmark_rmse"] for s in seeds]
            k = sum(known) / len(known)
            for m, pl in cases[1:]:
                r = [metrics(jobs[(w, s, f, m, pl)][0]) for s in seeds]
                c = [100 * x["association"]["correct_fraction"] for x in r]
                c_all = [100 * x["association"]["ceiling"]["run_correct_fraction"] for x in r]
                rmse = sum(x["landmark_rmse"] for x in r) / len(r)
                lm = round(sum(x["association"]["landmarks_final"] for x in r) / len(r))
                sp = sum(x["association"]["spurious_landmarks"] for x in r)
                dup = sum(x["association"]["duplicate_landmarks"] for x in r)
                sec = sum(x["association"]["seconds"] for x in r) / len(r)
                gate = "exact" if f.startswith("ekf") else a.gate
                print(f"| {w} | {f} | {gate} | {m} | {pl} | {sum(c) / len(c):.2f} % ({min(c):.2f}) "
                      f"| {sum(c_all) / len(c_all):.2f} % | {lm} ({sp}, {dup}) "
                      f"| {rmse:.3f} | {k:.3f} | {rmse / k:.2f} | {sec:.2f} |")

    print()
    print("| world | ceiling, individually (worst seed) | ceiling, jointly (worst seed) |")
    print("|---|---:|---:|")
    for w in worlds:
        ceilings = [metrics(jobs[(w, s, filters[0], "nn", a.provisional.split(",")[0])][0])["association"]["ceiling"]
                    for s in seeds]
        ind = [100 * c["individual_fraction"] for c in ceilings]
        joint = [100 * c["joint_fraction"] for c in ceilings]
        print(f"| {w} | {sum(ind) / len(ind):.2f} % ({min(ind):.2f}) | {sum(joint) / len(joint):.2f} % ({min(joint):.2f}) |")


if __name__ == "__main__":
    main()
