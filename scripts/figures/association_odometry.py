"""Unknown data association on uniform-200 with the odometry made better, the sensor kept.

The uniform world at the paper's density (200 landmarks, about 6 in range, each 7 cm from
its nearest neighbour on average) under the paper's sensor (sigma_range 4.5 cm) with one
false detection per scan and 10 % missed. Its odometry is the paper's: sigma_v 0.01 m/s at
a nominal 0.02 m/s, so a step's advance is uncertain by half of itself. This study scales
both control noises (sigma_v, sigma_w) by each factor given and keeps everything else, seeds
included: the EKF then runs each log with known association (`--drop-unlabelled`), `nn` and
`jcbb`. The table gives the share of the labelled observations associated correctly, the
aligned trajectory error (ATE) beside dead reckoning's, and the aligned map error, each the
mean over the seeds.

It separates two causes of the gap to the ceiling (the true map seen from the true pose,
about 91 %): a robot that loses its place along its path (its ATE above dead reckoning's),
and neighbouring landmarks confused where the robot knows its place.

Run:  PYTHONPATH=build/python /usr/bin/python3 scripts/figures/association_odometry.py [--scales 1,0.2,0.05]
      [--seeds 3] [--jobs 2] [--out out/association-odometry]
"""
import argparse
import concurrent.futures
import os

import seif
from association_study import metrics, run as run_cli  # the sibling study's CLI helpers

METHODS = ["known", "nn", "jcbb"]


def simulate(folder, scale, seed):
    c = seif.preset_config(seif.WorldPreset("uniform"), 200, 0, seed)
    c.clutter, c.detection_probability = 1.0, 0.9
    n = c.noise
    c.noise = seif.NoiseModel(n.sigma_v * scale, n.sigma_w * scale, n.sigma_range, n.sigma_bearing)
    os.makedirs(folder, exist_ok=True)
    seif.write_mrclam(folder, seif.simulate(c))
    return c.noise


def run(world, method):
    out = os.path.join(world, method)
    extra = ["--drop-unlabelled"] if method == "known" else []
    run_cli(["run", "--dataset", world, "--filter", "ekf", "--association", method, *extra, "--out", out])
    return metrics(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scales", default="1,0.2,0.05", help="factors on sigma_v and sigma_w")
    p.add_argument("--seeds", type=int, default=3, help="seeds 1..N")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--out", default="out/association-odometry")
    a = p.parse_args()
    scales = [float(s) for s in a.scales.split(",")]
    seeds = range(1, a.seeds + 1)
    noise = {}  # the scaled noise, the same for every seed
    for scale in scales:
        for seed in seeds:
            noise[scale] = simulate(os.path.join(a.out, f"x{scale}-seed{seed}"), scale, seed)
    jobs = [(scale, seed, m) for scale in scales for seed in seeds for m in METHODS]
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        results = dict(zip(jobs, pool.map(lambda j: run(os.path.join(a.out, f"x{j[0]}-seed{j[1]}"), j[2]), jobs)))

    def mean(values):
        return sum(values) / len(values)

    rows = ["| odometry | sigma_v [m/s], sigma_w [rad/s] | correct of all labelled, nn / jcbb (ceiling, jointly) "
            "| ATE [m] known / nn / jcbb (dead reckoning) | map RMSE [m] known / nn / jcbb |",
            "|---|---|---|---|---|"]
    for scale in scales:
        r = {m: [results[(scale, s, m)] for s in seeds] for m in METHODS}
        # The comparable share: correct over every labelled observation (the ceiling's count).
        share = {m: mean([x["association"]["ceiling"]["run_correct_fraction"] for x in r[m]]) for m in ("nn", "jcbb")}
        ceiling = mean([x["association"]["ceiling"]["joint_fraction"] for x in r["nn"]])
        ate = {m: mean([x["ate_rmse"] for x in r[m]]) for m in METHODS}
        dr = mean([x["dead_reckoning_ate_rmse"] for x in r["known"]])
        lm = {m: mean([x["landmark_rmse"] for x in r[m]]) for m in METHODS}
        rows.append(f"| x{scale:g} | {noise[scale].sigma_v:.4g}, {noise[scale].sigma_w:.4g} "
                    f"| {100 * share['nn']:.1f} / {100 * share['jcbb']:.1f} % ({100 * ceiling:.1f} %) "
                    f"| {ate['known']:.3f} / {ate['nn']:.3f} / {ate['jcbb']:.3f} ({dr:.3f}) "
                    f"| {lm['known']:.3f} / {lm['nn']:.3f} / {lm['jcbb']:.3f} |")
    table = "\n".join(rows)
    print(table)
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(table + "\n")


if __name__ == "__main__":
    main()
