#!/usr/bin/python3
"""Figures of `seif consistency`, from the nees.json it writes.

Usage: /usr/bin/python3 scripts/figures/consistency.py DIR

Writes, one figure per frame, each with a pose panel (3 dof) and a landmark panel (2 dof):
  DIR/nees_global.png    NEES in the global frame against the step
  DIR/nees_relative.png  NEES relative to the first landmark each filter mapped
Each curve is the mean over the runs; the grey band is the chi-square 95 % band of that
mean for the number of runs; the dashed line is the expected value (the dof). A smoother
(batch) has a value only at the last step, drawn as a marker. The NEES axis is logarithmic.
"""
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def finite(v):
    return v is not None and math.isfinite(v) and v > 0


def panel(ax, data, key, band, dof, title):
    steps = data["sample_steps"]
    ax.axhspan(band[0], band[1], color="0.85", label="95 % band")
    ax.axhline(dof, color="0.4", linestyle="--", linewidth=0.8)
    for f in data["filters"]:
        ys = f["nees"][key]
        pts = [(s, y) for s, y in zip(steps, ys) if finite(y)]
        if not pts:
            continue
        if len(pts) == 1:
            ax.plot([pts[0][0]], [pts[0][1]], "o", label=f["name"])
        else:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], label=f["name"], linewidth=1.2)
    ax.set_yscale("log")
    ax.set_xlabel("step")
    ax.set_ylabel("mean NEES")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = Path(sys.argv[1])
    data = json.loads((out / "nees.json").read_text())
    w = data["world"]
    where = w["preset"] + (f" ({w['path']})" if w.get("path") else "")
    band = data["band95"]
    for frame, suffix, name in (("global", "", "nees_global.png"), ("relative to the first landmark", "_relative", "nees_relative.png")):
        fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
        panel(axes[0], data, "pose" + suffix, band["pose"], 3, f"pose NEES (3 dof), {frame}")
        panel(axes[1], data, "landmark" + suffix, band["landmark"], 2, f"landmark NEES (2 dof, mean over the map), {frame}")
        axes[1].legend(fontsize=8, loc="upper left")
        fig.suptitle(f"{where}: {data['runs']} runs")
        fig.tight_layout()
        fig.savefig(out / name, dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main()
