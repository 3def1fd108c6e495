"""A SEIF in your own loop: a robot driver that calls predict/update and reads the pose.

Symbols used below:
  seif.make_filter(spec, start, config)  builds a filter ("seif", "ekf", "eif", "batch")
  seif.NoiseModel                         the noise standard deviations of driver and sensor
  seif.paper_filter_config(noise)         a FilterConfig with the velocity motion model and a
                                          range-bearing sensor of that noise
  seif.VelocityControl(v, w, dt)          forward speed v [m/s], turn rate w [rad/s] for dt [s]
  seif.Observation(id, z)                 z = (range [m], bearing [rad]) of landmark `id`
  filter.predict(u) / filter.update(zs)   the motion and the measurement update
  filter.pose(), pose_covariance()        the estimate (x, y, theta) and its 3x3 covariance
  truth, landmarks, rng                   this script's own simulated robot (numpy only)

Run:  PYTHONPATH=build/python /usr/bin/python3 examples/python/own_loop.py
"""
import numpy as np

import seif

# --- 1. The world our "robot" lives in: 12 landmarks on a ring of radius 4 m. -----------------
rng = np.random.default_rng(42)
angles = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
landmarks = {i: np.array([4.0 * np.cos(a), 4.0 * np.sin(a)]) for i, a in enumerate(angles)}

# --- 2. The filter: noise standard deviations the driver and sensor really have. --------------
noise = seif.NoiseModel(sigma_v=0.05, sigma_w=0.02, sigma_range=0.1, sigma_bearing=0.02)
config = seif.paper_filter_config(noise)
start = np.array([2.0, 0.0, np.pi / 2])  # x [m], y [m], heading [rad]
slam = seif.make_filter("seif", start, config)

# --- 3. The driver: drive a circle of radius 2 m at 0.5 m/s, 10 Hz, for two laps. -------------
v, w, dt = 0.5, 0.25, 0.1
truth = start.copy()
sensor_range = 3.5  # [m]
for k in range(int(2 * 2 * np.pi / (w * dt))):
    # 3a. What the robot really does: the commanded (v, w) plus actuator noise.
    v_true = v + rng.normal(0.0, noise.sigma_v)
    w_true = w + rng.normal(0.0, noise.sigma_w)
    truth = seif.VelocityModel(0.0, 0.0).apply(truth, seif.VelocityControl(v_true, w_true, dt))

    # 3b. The filter predicts with what the driver commanded.
    slam.predict(seif.VelocityControl(v, w, dt))

    # 3c. The sensor: range and bearing of each landmark within range, with noise.
    observations = []
    for lid, p in landmarks.items():
        d = p - truth[:2]
        r = np.hypot(*d)
        if r < sensor_range:
            bearing = seif.wrap_angle(np.arctan2(d[1], d[0]) - truth[2])
            z = np.array([r + rng.normal(0.0, noise.sigma_range),
                          bearing + rng.normal(0.0, noise.sigma_bearing)])
            observations.append(seif.Observation(lid, z))
    slam.update(observations)

    # 3d. Read the estimate, e.g. for a controller or a display.
    if k % 50 == 0:
        x = slam.pose()
        sd = np.sqrt(np.diag(slam.pose_covariance()))
        print(f"step {k:3d}: pose ({x[0]:6.3f}, {x[1]:6.3f}, {x[2]:6.3f}) "
              f"+- ({sd[0]:.3f} m, {sd[1]:.3f} m, {sd[2]:.3f} rad), "
              f"true ({truth[0]:6.3f}, {truth[1]:6.3f}), {len(slam.landmark_ids())} landmarks")

# --- 4. The map: every landmark's estimate against the truth. --------------------------------
errors = [np.linalg.norm(slam.landmark(lid) - landmarks[lid]) for lid in slam.landmark_ids()]
print(f"final pose error {np.linalg.norm(slam.pose()[:2] - truth[:2]):.3f} m, "
      f"landmark error mean {np.mean(errors):.3f} m over {len(errors)} landmarks, "
      f"{slam.stats().links} links in H")
