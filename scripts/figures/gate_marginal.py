"""How the SEIF's local (or conservative) gate marginal compares with the exact one, by blanket bound.

For every 10th step of a simulated world (known association), each observation of a mapped
landmark is predicted with S = J Sigma J^T + R twice: Sigma the exact joint marginal of the
pose and the landmark, and Sigma the local one (H inverted over a blanket of at most
`blanket` variables besides the two; 0: the whole Markov blanket). The local S is never
larger; the table gives how much smaller, as the largest eigenvalue of S_local^-1 S_exact
(1: equal; 2: the exact innovation is twice as spread along some direction), and the
Mahalanobis distance of the actual innovation under each (the gate tests d2 <= 9.21).
With --mode conservative the second S comes from the conservative marginal, an upper bound:
never smaller, and the table gives how much larger, lambda_max(S_exact^-1 S_conservative).

Run:  PYTHONPATH=build/python /usr/bin/python3 scripts/figures/gate_marginal.py [--preset park] [--seed 1]
      [--mode local|conservative] [--blankets 0,4,8,16,32,64]
"""
import argparse

import numpy as np

import seif

BLANKETS = [0, 4, 8, 16, 32, 64]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--preset", default="park", choices=["park", "paper", "uniform"])
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--filters", default="seif,seif:profile=consistent")
    p.add_argument("--mode", default="local", choices=["local", "conservative"])
    p.add_argument("--blankets", default=",".join(str(b) for b in BLANKETS))
    args = p.parse_args()
    blankets = [int(b) for b in args.blankets.split(",")]
    mode = seif.MarginalMode.Local if args.mode == "local" else seif.MarginalMode.Conservative
    ratio_name = "S_local^-1 S_exact" if args.mode == "local" else "S_exact^-1 S_conservative"

    preset = {"park": seif.WorldPreset.Park, "paper": seif.WorldPreset.Paper, "uniform": seif.WorldPreset.Uniform}
    world = seif.preset_config(preset[args.preset], seed=args.seed)
    data = seif.build_dataset(seif.simulate(world))
    config = seif.paper_filter_config(world.noise)
    start = seif.start_pose(data)
    steps = data.steps
    print(f"{args.preset}, seed {args.seed}: {len(steps)} steps")
    print(f"| filter | blanket | lambda_max({ratio_name}) median / p90 / max | d2 exact median / p90 | d2 {args.mode} median / p90 | true pairing outside the 0.99 gate, exact / {args.mode} |")
    print("|---|---:|---|---|---|---|")
    for spec in seif.split_filter_list(args.filters):
        filters = {b: seif.make_filter(f"{spec}{',' if ':' in spec else ':'}blanket={b}", start, config) for b in blankets}
        ratio = {b: [] for b in blankets}
        d2 = {b: [] for b in blankets}
        d2_exact = []
        for k, step in enumerate(steps):
            for f in filters.values():
                f.predict(step.u)
            if k % 10 == 0 and k > 0:
                ref = filters[blankets[0]]
                for z in step.observations:
                    if not ref.has_landmark(z.landmark):
                        continue
                    pe = ref.predict_measurement(z.landmark, mode=seif.MarginalMode.Exact)
                    nu = np.array(z.z) - pe.z
                    nu[1] = (nu[1] + np.pi) % (2 * np.pi) - np.pi
                    d2_exact.append(nu @ np.linalg.solve(pe.S, nu))
                    for b, f in filters.items():
                        pl = f.predict_measurement(z.landmark, mode=mode)
                        small, large = (pl.S, pe.S) if args.mode == "local" else (pe.S, pl.S)
                        ratio[b].append(np.linalg.eigvals(np.linalg.solve(small, large)).real.max())
                        d2[b].append(nu @ np.linalg.solve(pl.S, nu))
            for f in filters.values():
                f.update(step.observations)
        de = np.array(d2_exact)
        for b in blankets:
            r = np.array(ratio[b])
            dl = np.array(d2[b])
            print(f"| {spec} | {b if b else 'Markov'} | {np.median(r):.2f} / {np.percentile(r, 90):.2f} / {r.max():.1f} "
                  f"| {np.median(de):.2f} / {np.percentile(de, 90):.2f} | {np.median(dl):.2f} / {np.percentile(dl, 90):.2f} "
                  f"| {100 * np.mean(de > 9.21):.2f} % / {100 * np.mean(dl > 9.21):.2f} % |")


if __name__ == "__main__":
    main()
