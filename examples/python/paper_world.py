"""The paper's simulated world (Thrun et al. 2002): the SEIF against the EKF.

Symbols used below:
  seif.simulated_dataset("paper", seed=s)  the simulator's world: 50 landmarks in the unit
                                           square, 500 steps; returns (dataset, world config)
  seif.start_pose(dataset)                 the true start pose (the filters start there)
  seif.run_filter(filter, dataset)         the library's run loop: every step, then finish()
  seif.landmark_rmse(filter, truth, a)     RMS landmark error [m] (a: Alignment.Rigid or Unaligned)
  filter.stats()                           the structure of the information matrix H
  filter.information()                     H as scipy.sparse.csc_matrix

Run:  PYTHONPATH=build/python /usr/bin/python3 examples/python/paper_world.py
"""
import numpy as np

import seif

# --- 1. One simulated run: the data every filter sees. ---------------------------------------
data, world = seif.simulated_dataset("paper", seed=1)
print(f"paper world: {len(data.landmarks)} landmarks, {len(data)} steps, "
      f"sensor range {world.sensor_range} m")

# --- 2. The filters, built with the world's true noise and the paper's models. ---------------
config = seif.paper_filter_config(world.noise)
filters = {spec: seif.make_filter(spec, seif.start_pose(data), config)
           for spec in ("ekf", "seif", "seif:mean=exact")}

# --- 3. Run each over the same data and compare. --------------------------------------------
print(f"{'filter':16s} {'map RMSE [m]':>12s} {'aligned [m]':>11s} {'links':>6s} {'us/step':>8s} {'H nnz':>7s}")
for spec, f in filters.items():
    out = seif.run_filter(f, data)
    rmse = seif.landmark_rmse(f, data.landmarks, seif.Alignment.Unaligned)
    aligned = seif.landmark_rmse(f, data.landmarks, seif.Alignment.Rigid)
    H = f.information()  # scipy.sparse: the SEIF's stays sparse, the EKF's is dense
    print(f"{spec:16s} {rmse:12.4f} {aligned:11.4f} {out.final_stats.links:6d} "
          f"{1e6 * out.seconds / out.steps:8.1f} {H.nnz:7d}")

# --- 4. What sparsity means: the SEIF's robot is linked to at most `active` (theta_x) landmarks. --
seif_filter = filters["seif"]
print(f"SEIF active landmarks now: {seif_filter.active_landmarks()} "
      f"(active = {seif_filter.options.active})")
ekf_pose, seif_pose = filters["ekf"].pose(), seif_filter.pose()
print(f"final poses differ by {np.linalg.norm(ekf_pose[:2] - seif_pose[:2]):.4f} m")
