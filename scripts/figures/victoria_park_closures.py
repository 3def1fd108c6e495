#!/usr/bin/python3
"""How the filters carry Victoria Park's loop closures into the trees mapped before them.

Usage: victoria_park_closures.py [--data DIR] [--seif BIN] [--out DIR] [--jobs N]

Runs `seif run` on the park (known association) once per filter with `--smooth` (the batch
MAP is the reference: the trees have no surveyed positions), then once per filter and time
with `--checkpoint-every STEP`, and reads each checkpoint with the Python module. Per time it
prints, for the trees first seen in the two excursions (ids 600-659, mapped at t = 1068-1079 s
and 700-899, at t = 1290-1330 s), their mean distance to the batch's map — the filter's own
estimate and, for the SEIF, its posterior mean H^-1 b — the robot's distance to the batch
trajectory, and the SEIF's standard deviations of those trees as a multiple of the EKF's.
Then the final map's distance to the batch map over blocks of 50 ids.

Needs the build's Python module on PYTHONPATH (build/python). About 10 minutes on two cores
(the exact-mean SEIF takes 80 s a run).
"""
import argparse
import concurrent.futures
import os
import subprocess
import sys

import numpy as np

import seif

EKF = "ekf:linearization=invariant,iterations=3"
PROFILE = "seif:profile=consistent"
EXACT = "seif:profile=consistent,mean=exact"
FILTERS = [EKF, PROFILE, EXACT]
TIMES = [1095, 1135, 1175, 1260, 1300, 1340, 1380, 1420, 1440, 1460]
GROUPS = {"600-659": (600, 660), "700-899": (700, 900)}


def run(binary, data, spec, out, extra=()):
    os.makedirs(out, exist_ok=True)
    cmd = [binary, "run", "--dataset", data, "--filter", spec, "--out", out, *extra]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{done.stderr}")
    return out


def read_map(path):
    m = np.genfromtxt(path, delimiter=",", names=True)
    return {int(i): np.array([x, y]) for i, x, y in zip(m["id"], m["x"], m["y"])}


def group_distance(points, batch, lo, hi):
    d = [np.linalg.norm(p - batch[i]) for i, p in points.items() if lo <= i < hi and i in batch]
    return np.mean(d) if d else float("nan")


def measure(path, batch, batch_xy, step):
    f = seif.load(path)
    ids = f.landmark_ids()
    own = {i: np.asarray(f.landmark(i)) for i in ids}
    row = {"robot": float(np.linalg.norm(np.asarray(f.pose())[:2] - batch_xy[step]))}
    for name, (lo, hi) in GROUPS.items():
        row[name] = group_distance(own, batch, lo, hi)
    post = f.posterior_mean()
    if post is not None:
        pm = {i: post[3 + 2 * k:5 + 2 * k] for k, i in enumerate(ids)}
        for name, (lo, hi) in GROUPS.items():
            row[name + " posterior"] = group_distance(pm, batch, lo, hi)
    sd = np.sqrt(np.diag(f.covariance()))
    row["sd"] = {i: sd[3 + 2 * k:5 + 2 * k] for k, i in enumerate(ids)}
    return row


def fmt(x):
    return "–" if x is None or np.isnan(x) else f"{x:.1f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="../shared/data/victoria-park")
    ap.add_argument("--seif", default="build/bin/seif")
    ap.add_argument("--out", default="out/victoria_park_closures")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    if not os.path.isdir(a.data):
        sys.exit(f"{a.data}: no Victoria Park folder")

    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        finals = {s: pool.submit(run, a.seif, a.data, s, os.path.join(a.out, f"final{k}"), ["--smooth"])
                  for k, s in enumerate(FILTERS)}
        finals = {s: f.result() for s, f in finals.items()}
        batch = read_map(os.path.join(finals[EKF], "map.csv"))
        traj = np.loadtxt(os.path.join(finals[EKF], "trajectory.tum"), comments="#")
        steps = {t: int(np.searchsorted(traj[:, 0], t)) for t in TIMES}
        jobs = {}
        for k, s in enumerate(FILTERS):
            for t, step in steps.items():
                ck = os.path.join(a.out, f"f{k}-{step}.ck")
                jobs[(s, t)] = pool.submit(run, a.seif, a.data, s, os.path.join(a.out, f"f{k}-{step}"),
                                           ["--checkpoint-every", str(step), "--checkpoint", ck])
        for j in jobs.values():
            j.result()

    print("Distance to the batch MAP [m] of the robot and of the trees first seen in each excursion; "
          "SEIF sd / EKF sd over the trees 700-899.\n")
    print("| t [s] | EKF: robot, 600-659, 700-899 | profile: robot, 600-659, 700-899 | "
          "profile's posterior H⁻¹b: 600-659, 700-899 | profile, exact mean: robot, 600-659, 700-899 | "
          "sd ratio (exact mean / EKF) |")
    print("|---:|---|---|---|---|---:|")
    for t, step in steps.items():
        rows = {s: measure(os.path.join(a.out, f"f{k}-{step}.ck"), batch, traj[:, 1:3], step)
                for k, s in enumerate(FILTERS)}
        e, p, x = rows[EKF], rows[PROFILE], rows[EXACT]
        ratios = [np.mean(x["sd"][i] / e["sd"][i]) for i in e["sd"] if 700 <= i < 900 and i in x["sd"]]
        ratio = f"{np.mean(ratios):.2f}" if ratios else "–"
        print(f"| {t} | {fmt(e['robot'])}, {fmt(e['600-659'])}, {fmt(e['700-899'])} "
              f"| {fmt(p['robot'])}, {fmt(p['600-659'])}, {fmt(p['700-899'])} "
              f"| {fmt(p.get('600-659 posterior'))}, {fmt(p.get('700-899 posterior'))} "
              f"| {fmt(x['robot'])}, {fmt(x['600-659'])}, {fmt(x['700-899'])} "
              f"| {ratio} |")

    print("\nThe final map (after finish()) against the batch's, mean distance [m] per block of 50 ids:\n")
    blocks = list(range(0, 900, 50))
    print("| filter | " + " | ".join(f"{b}-" for b in blocks) + " |")
    print("|---|" + "---:|" * len(blocks))
    for s, out in finals.items():
        own = read_map(os.path.join(out, "map_filter.csv"))
        print(f"| `{s}` | " + " | ".join(fmt(group_distance(own, batch, b, b + 50)) for b in blocks) + " |")


if __name__ == "__main__":
    main()
