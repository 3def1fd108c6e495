#!/usr/bin/python3
"""Figures of `seif paper` (Thrun et al. 2002, figures 1, 2 and 6), from the data it writes.

Usage: /usr/bin/python3 scripts/figures/paper.py DIR

Reads DIR/figure_data/{ekf,seif}.json (one typical run's final state -- `seif paper` picks
the run whose constant-time SEIF has the median final error: true and estimated
landmarks with 2x2 covariances, true and estimated path, the dense covariance and
information matrices ordered [x, y, theta, landmarks by id], the links of the information
matrix) and DIR/results.json, and writes:

  DIR/fig1_ekf.png       EKF map with 2-sigma ellipses, its correlation matrix, its
                         normalized information matrix (paper figure 1)
  DIR/fig2_seif.png      the SEIF's sparse normalized information matrix and its network of
                         links over the map (paper figure 2)
  DIR/fig6_compare.png   EKF (top) and SEIF (bottom): map, links (robot-landmark red,
                         landmark-landmark green), correlation, normalized information
                         (paper figure 6)
  DIR/sweep_active.png   error and time per update against theta_x (when the sweep ran)

Matrices are drawn as in the paper: dark = strong. Correlation |S_ij| / sqrt(S_ii S_jj) on
[0, 1]; normalized information |H_ij| / sqrt(H_ii H_jj), whose off-diagonal entries are much
smaller than its unit diagonal, on [0, max off-diagonal] (the diagonal saturates).
"""
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.patches import Ellipse  # noqa: E402

ROBOT_LINK = (0.85, 0.1, 0.1)
LANDMARK_LINK = (0.1, 0.6, 0.1)


def load(path):
    with open(path) as f:
        return json.load(f)


def normalized(m):
    d = np.sqrt(np.abs(np.diag(m)))
    d[d == 0] = 1.0
    return np.abs(m) / np.outer(d, d)


def matrix_panel(ax, m, title, offdiag_scale):
    """Dark = strong. offdiag_scale: the colour scale tops out at the largest off-diagonal
    entry (for the normalized information matrix, whose diagonal is 1 and dwarfs the rest)."""
    a = normalized(m)
    vmax = 1.0
    if offdiag_scale:
        off = a.copy()
        np.fill_diagonal(off, 0.0)
        vmax = max(off.max(), 1e-12)
    ax.imshow(a, cmap="gray_r", vmin=0.0, vmax=vmax, interpolation="nearest")
    n = (a.shape[0] - 3) // 2
    ax.set_title(title, fontsize=9)
    ax.set_xticks([1, 3 + n])
    ax.set_xticklabels(["pose", f"landmarks 1..{n} (by id)"], fontsize=7)
    ax.set_yticks([])
    for v in (2.5,):
        ax.axhline(v, color=(0.6, 0.6, 1.0), lw=0.5)
        ax.axvline(v, color=(0.6, 0.6, 1.0), lw=0.5)


def draw_robot(ax, pose, size=0.035, color="k"):
    x, y, th = pose
    tri = np.array([[size, 0], [-0.6 * size, 0.5 * size], [-0.6 * size, -0.5 * size]])
    c, s = np.cos(th), np.sin(th)
    pts = tri @ np.array([[c, s], [-s, c]]) + np.array([x, y])
    ax.fill(pts[:, 0], pts[:, 1], color=color, zorder=6)


def map_panel(ax, d, title):
    """Estimated map with 2-sigma ellipses, true landmarks, true and estimated path."""
    tp = np.array(d["true_path"])
    ep = np.array(d["path"])
    ax.plot(tp[:, 1], tp[:, 2], color=(0.75, 0.75, 0.75), lw=0.8, label="true path")
    ax.plot(ep[:, 1], ep[:, 2], color=(0.2, 0.4, 0.9), lw=0.6, label="estimated path")
    tl = np.array([[l["x"], l["y"]] for l in d["true_landmarks"]])
    ax.plot(tl[:, 0], tl[:, 1], "x", color=(0.5, 0.5, 0.5), ms=4, label="true landmarks")
    for l in d["landmarks"]:
        cov = np.array(l["cov"])
        w, v = np.linalg.eigh(cov)
        w = np.maximum(w, 0.0)
        angle = np.degrees(np.arctan2(v[1, 1], v[0, 1]))
        ax.add_patch(Ellipse((l["x"], l["y"]), 2 * 2 * np.sqrt(w[1]), 2 * 2 * np.sqrt(w[0]),
                             angle=angle, fill=False, ec="k", lw=0.6))
        ax.plot(l["x"], l["y"], ".", color="k", ms=3)
    draw_robot(ax, d["pose"])
    pc = np.array(d["pose_cov"])[:2, :2]
    w, v = np.linalg.eigh(pc)
    ax.add_patch(Ellipse(d["pose"][:2], 4 * np.sqrt(max(w[1], 0)), 4 * np.sqrt(max(w[0], 0)),
                         angle=np.degrees(np.arctan2(v[1, 1], v[0, 1])), fill=False, ec="r", lw=0.8))
    ax.set_xlim(-0.05, 1.05)
    ax.set_ylim(-0.05, 1.05)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x [m]", fontsize=8)
    ax.set_ylabel("y [m]", fontsize=8)
    ax.tick_params(labelsize=7)


def links_panel(ax, d, title):
    """Landmarks as disks (active ones black), the robot, and every link of the information
    matrix: robot-landmark red, landmark-landmark green; opacity grows with the normalized
    link strength."""
    pos = {l["id"]: (l["x"], l["y"]) for l in d["landmarks"]}
    robot = tuple(d["pose"][:2])
    rl, ll = d["robot_links"], d["landmark_links"]
    smax = max([l["strength"] for l in rl + ll] + [1e-12])

    def rgba(color, s):
        return (*color, 0.08 + 0.92 * np.sqrt(s / smax))

    segs = [[pos[l["a"]], pos[l["b"]]] for l in ll]
    cols = [rgba(LANDMARK_LINK, l["strength"]) for l in ll]
    ax.add_collection(LineCollection(segs, colors=cols, linewidths=0.8, linestyles="--", zorder=2))
    segs = [[robot, pos[l["id"]]] for l in rl]
    cols = [rgba(ROBOT_LINK, l["strength"]) for l in rl]
    ax.add_collection(LineCollection(segs, colors=cols, linewidths=1.2, zorder=3))
    active = {l["id"] for l in rl}
    for i, (x, y) in pos.items():
        ax.plot(x, y, "o", ms=5, mfc="k" if i in active and len(active) < len(pos) else "w",
                mec="k", mew=0.7, zorder=4)
    draw_robot(ax, d["pose"])
    ax.set_xlim(-0.05, 1.05)
    ax.set_ylim(-0.05, 1.05)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x [m]", fontsize=8)
    ax.set_ylabel("y [m]", fontsize=8)
    ax.tick_params(labelsize=7)


def err(d):
    return f"final error {1e3 * d['final_error']:.2f}·10⁻³ m²" if "final_error" in d else ""


def label(d):
    return {"ekf": "EKF", "seif": "SEIF (constant time)", "seif_exact": "SEIF with exact μ"}[d["filter"]]


def fig1(ekf, out):
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.4))
    map_panel(axes[0], ekf, f"EKF map, 2σ ellipses (seed {ekf['seed']}, {err(ekf)})")
    matrix_panel(axes[1], ekf["covariance"], "correlation matrix |Σij|/√(Σii Σjj)", False)
    matrix_panel(axes[2], ekf["information"],
                 "normalized information matrix |Hij|/√(Hii Hjj)\n(scale: 0 .. largest off-diagonal)",
                 True)
    axes[0].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.06), ncol=3, frameon=False)
    fig.suptitle("Figure 1: EKF SLAM, 50 landmarks (dark = strong)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=130, bbox_inches="tight")
    plt.close(fig)


def fig2(seif, out):
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 4.6))
    matrix_panel(axes[0], seif["information"],
                 f"SEIF sparse normalized information matrix\n({seif['links']} links; scale 0 .. largest off-diagonal)",
                 True)
    links_panel(axes[1], seif,
                f"network of links: {len(seif['robot_links'])} active landmarks (black),\n"
                f"robot links red, landmark links green dashed")
    fig.suptitle("Figure 2: the SEIF's sparse information matrix and its network of links", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def fig6(ekf, seif, out):
    fig, axes = plt.subplots(2, 4, figsize=(17, 8.6))
    for row, d in enumerate((ekf, seif)):
        name = label(d)
        map_panel(axes[row, 0], d, f"{name}: final map, 2σ ellipses\n({err(d)})")
        links_panel(axes[row, 1], d, f"{name}: {d['links']} links\n"
                                     f"(red robot–landmark: {len(d['robot_links'])}, "
                                     f"green landmark–landmark: {len(d['landmark_links'])})")
        matrix_panel(axes[row, 2], d["covariance"], f"{name}: correlation matrix", False)
        matrix_panel(axes[row, 3], d["information"], f"{name}: normalized information matrix", True)
    fig.suptitle(f"Figure 6: EKF (top) vs SEIF (bottom), N = 50, same data: seed {ekf['seed']}, "
                 f"the run with the median SEIF error; dark = strong", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def sweep(results, out):
    rows = results["sweep_active"]
    ekf = next(f for f in results["filters"] if f["name"] == "ekf")
    th = np.array([r["active"] for r in rows])
    err = 1e3 * np.array([r["error_mean"] for r in rows])
    ci = 1e3 * np.array([r["error_ci95"] for r in rows])
    us = np.array([r["us_per_update_median"] for r in rows])
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    ax = axes[0]
    e, c = 1e3 * ekf["error_mean"], 1e3 * ekf["error_ci95"]
    ax.axhspan(e - c, e + c, color=(0.8, 0.8, 0.8), label="EKF (95% CI)")
    ax.axhline(e, color="k", lw=0.8)
    ax.errorbar(th, err, yerr=ci, fmt="o-", capsize=3, label="constant-time SEIF (95% CI)")
    journal = [(r["active"], r["journal_error_ratio_to_ekf"] * e) for r in rows
               if r.get("journal_error_ratio_to_ekf") is not None]
    if journal:
        ax.plot(*zip(*journal), "s", mfc="none", color="tab:red",
                label="journal version (ratio to its EKF) × our EKF")
    ax.set_xlabel("θx (active landmarks)")
    ax.set_ylabel("final error [10⁻³ m²]")
    ax.set_xticks(th)
    ax.legend(fontsize=7)
    ax.set_title(f"final map error ({ekf['runs']} runs)", fontsize=9)
    ax = axes[1]
    ax.axhline(ekf["us_per_update_median"], color="k", lw=0.8, label="EKF")
    ax.plot(th, us, "o-", label="constant-time SEIF")
    ax.set_xlabel("θx (active landmarks)")
    ax.set_ylabel("time per update, median [µs]")
    ax.set_xticks(th)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    ax.set_title("time per update", fontsize=9)
    fig.suptitle("Constant-time SEIF against the number of active landmarks (N = 50)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = Path(sys.argv[1])
    data = out / "figure_data"
    ekf = load(data / "ekf.json")
    seif = load(data / "seif.json")
    fig1(ekf, out / "fig1_ekf.png")
    fig2(seif, out / "fig2_seif.png")
    fig6(ekf, seif, out / "fig6_compare.png")
    results_file = out / "results.json"
    if results_file.exists():
        results = load(results_file)
        if results.get("sweep_active"):
            sweep(results, out / "sweep_active.png")


if __name__ == "__main__":
    main()
