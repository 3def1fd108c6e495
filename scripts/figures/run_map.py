#!/usr/bin/python3
"""Figure of one or more `seif run` outputs over the same dataset: trajectories, maps and,
when given, GPS fixes and dead reckoning, in the GPS frame (or the first run's frame).

Usage: /usr/bin/python3 scripts/figures/run_map.py OUT.png [--gps GPS] [--ellipses] [--title T] RUN_DIR[=LABEL]...

Each RUN_DIR holds trajectory.tum, map.csv and (optionally) dead_reckoning.tum from `seif
run`; `seif plot RUN_DIR` draws one with its gps.csv and ellipses into RUN_DIR/map.png.
--ellipses draws each landmark's 95 % covariance ellipse (map.csv's cov_xx, cov_xy, cov_yy).
With --gps (time x y per line, '#' comments, or a CSV "time,x,y" such as `seif run`'s
gps.csv), each trajectory and its map are moved by
the rigid 2-D motion that best aligns the trajectory, interpolated at the GPS stamps, to the
fixes (least squares, as metrics.json's gps_rmse); the first run's dead reckoning is drawn
aligned the same way (its own best fit). Without --gps, everything is drawn as estimated.
Exits with status 3 when matplotlib is not installed.
"""
import sys
from pathlib import Path

import numpy as np

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse
except ImportError:
    print("run_map.py: matplotlib is not installed", file=sys.stderr)
    sys.exit(3)

COLORS = ["tab:red", "tab:blue", "tab:green", "tab:purple"]


def read_table(path, columns):
    rows = [l.split() for l in Path(path).read_text().splitlines() if l.strip() and not l.lstrip().startswith("#")]
    return np.array([[float(v) for v in r[:columns]] for r in rows]).reshape(-1, columns)


def read_gps(path):
    """GPS fixes (time, x, y): a CSV with a header line, or a whitespace table."""
    text = Path(path).read_text()
    if text.lstrip().startswith("time,"):
        rows = [l.split(",") for l in text.splitlines()[1:] if l.strip()]
        return np.array([[float(v) for v in r[:3]] for r in rows]).reshape(-1, 3)
    return read_table(path, 3)


def read_map(path):
    """Landmark positions (N x 2) and their 2x2 covariances (N x 2 x 2, or None without)."""
    lines = Path(path).read_text().splitlines()
    header = lines[0].split(",") if lines else []
    rows = [[float(v) for v in l.split(",")] for l in lines[1:] if l.strip()]
    xy = np.array([r[1:3] for r in rows]).reshape(-1, 2)
    if "cov_xx" not in header:
        return xy, None
    i, j, k = header.index("cov_xx"), header.index("cov_xy"), header.index("cov_yy")
    cov = np.array([[[r[i], r[j]], [r[j], r[k]]] for r in rows]).reshape(-1, 2, 2)
    return xy, cov


CHI2_95_2DOF = 5.991  # the 95 % quantile of chi-square with 2 degrees of freedom


def draw_ellipses(ax, xy, cov, color):
    """The 95 % ellipse of each landmark (x - m)^T P^-1 (x - m) = 5.991."""
    for m, P in zip(xy, cov):
        w, v = np.linalg.eigh(P)
        w = np.maximum(w, 0.0)
        angle = np.degrees(np.arctan2(v[1, 1], v[0, 1]))
        ax.add_patch(Ellipse(m, 2 * np.sqrt(CHI2_95_2DOF * w[1]), 2 * np.sqrt(CHI2_95_2DOF * w[0]),
                             angle=angle, fill=False, ec=color, lw=0.5, alpha=0.7, zorder=4))


def rigid_fit(p, q):
    """R, t minimising sum |R p_i + t - q_i|^2 (2-D, no scale)."""
    cp, cq = p.mean(axis=0), q.mean(axis=0)
    a, b = p - cp, q - cq
    sxx = (a * b).sum()
    sxy = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum()
    ang = np.arctan2(sxy, sxx)
    R = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    return R, cq - R @ cp


def aligned(traj, gps):
    """The trajectory's (R, t) to the GPS frame, and the RMSE at the GPS stamps."""
    inside = (gps[:, 0] >= traj[0, 0]) & (gps[:, 0] <= traj[-1, 0])
    g = gps[inside]
    p = np.column_stack([np.interp(g[:, 0], traj[:, 0], traj[:, 1]), np.interp(g[:, 0], traj[:, 0], traj[:, 2])])
    R, t = rigid_fit(p, g[:, 1:3])
    rmse = np.sqrt((((p @ R.T + t) - g[:, 1:3]) ** 2).sum(axis=1).mean())
    return R, t, rmse


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 1
    out = argv[1]
    gps, title, runs, ellipses = None, "", [], False
    i = 2
    while i < len(argv):
        if argv[i] == "--gps":
            gps = read_gps(argv[i + 1])
            i += 2
        elif argv[i] == "--ellipses":
            ellipses = True
            i += 1
        elif argv[i] == "--title":
            title = argv[i + 1]
            i += 2
        else:
            d, _, label = argv[i].partition("=")
            runs.append((Path(d), label or Path(d).name))
            i += 1
    fig, ax = plt.subplots(figsize=(9, 8))
    if gps is not None:
        ax.plot(gps[:, 1], gps[:, 2], ".", color="0.6", ms=2.5, label=f"GPS fixes ({len(gps)})", zorder=1)
    for k, (d, label) in enumerate(runs):
        traj = read_table(d / "trajectory.tum", 3)
        lm, lm_cov = read_map(d / "map.csv")
        R, t, note = np.eye(2), np.zeros(2), ""
        if gps is not None:
            R, t, rmse = aligned(traj, gps)
            note = f", GPS RMSE {rmse:.2f} m"
        xy = traj[:, 1:3] @ R.T + t
        c = COLORS[k % len(COLORS)]
        ax.plot(xy[:, 0], xy[:, 1], "-", color=c, lw=0.9, label=f"{label} trajectory{note}", zorder=3)
        m = lm @ R.T + t
        ax.plot(m[:, 0], m[:, 1], "+", color=c, ms=5, mew=1.0, label=f"{label} map ({len(lm)} landmarks)", zorder=4)
        if ellipses and lm_cov is not None:
            draw_ellipses(ax, m, R @ lm_cov @ R.T, c)
            ax.plot([], [], "-", color=c, lw=0.5, label=f"{label} 95 % ellipses")
        dr_file = d / "dead_reckoning.tum"
        if k == 0 and dr_file.exists():
            dr = read_table(dr_file, 3)
            Rd, td, note = np.eye(2), np.zeros(2), ""
            if gps is not None:
                Rd, td, rmse = aligned(dr, gps)
                note = f", GPS RMSE {rmse:.1f} m"
            dxy = dr[:, 1:3] @ Rd.T + td
            ax.plot(dxy[:, 0], dxy[:, 1], ":", color="0.3", lw=0.8, label=f"dead reckoning{note}", zorder=2)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]" + (" (GPS frame)" if gps is not None else ""))
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
