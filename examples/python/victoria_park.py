"""Victoria Park (iSAM's relative-odometry version) with the SEIF, plotted to a PNG.

Symbols used below:
  DATA                               victoria-park-isam/victoria_park.txt of $SEIF_SHARED_DATA_DIR
                                     (default ../shared/data next to the repository), or argv[1]
  OUT                                the PNG written (argv[2], default victoria_park.png)
  seif.open_dataset(path)            the file as a stream of events, with .info (models, start)
  info.filter_config()               a FilterConfig with the dataset's motion and sensor models
  seif.run_filter(filter, source)    the library's run loop over the stream; returns RunOutput
  out.trajectory_array()             (n, 4) array: t, x [m], y [m], theta [rad]
  out.dead_reckoning_array()         the odometry integrated alone, same layout

Run:  PYTHONPATH=build/python /usr/bin/python3 examples/python/victoria_park.py
"""
import os
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt
import numpy as np

import seif

HERE = pathlib.Path(__file__).resolve().parent
SHARED = pathlib.Path(os.environ.get("SEIF_SHARED_DATA_DIR", HERE.parents[2] / "shared" / "data"))
DATA = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else SHARED / "victoria-park-isam" / "victoria_park.txt"
OUT = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else pathlib.Path("victoria_park.png")

# --- 1. Open the dataset: the reader tells the format and the models. ------------------------
source = seif.open_dataset(DATA)
info = source.info
print(f"{DATA.name}: format {info.format}\n  motion: {info.motion.describe()}\n  sensor: {info.sensor.describe()}")

# --- 2. A SEIF with the dataset's models, streamed over every event. -------------------------
slam = seif.make_filter("seif", info.start_pose, info.filter_config())
out = seif.run_filter(slam, source, progress=None)
print(f"  {out.steps} steps, {len(slam.landmark_ids())} landmarks, "
      f"{1e6 * out.seconds / out.steps:.1f} us/step, {out.final_stats.links} links in H")

# --- 3. The map: landmark estimates in state order. ------------------------------------------
ids = slam.landmark_ids()
landmarks = np.array([slam.landmark(i) for i in ids])

# --- 4. The plot: SEIF path, odometry alone, and the map. ------------------------------------
trajectory = out.trajectory_array()
dead_reckoning = out.dead_reckoning_array()
fig, ax = plt.subplots(figsize=(7, 7))
ax.plot(dead_reckoning[:, 1], dead_reckoning[:, 2], color="0.6", lw=0.8, label="odometry alone")
ax.plot(trajectory[:, 1], trajectory[:, 2], color="C0", lw=1.0, label="SEIF path")
ax.scatter(landmarks[:, 0], landmarks[:, 1], s=6, color="C3", label=f"SEIF map ({len(ids)} trees)")
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
ax.set_title("Victoria Park, SEIF")
ax.set_aspect("equal")
ax.legend(loc="best")
fig.tight_layout()
fig.savefig(OUT, dpi=120)
print(f"  wrote {OUT}")
