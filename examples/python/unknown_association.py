"""Mapping when the sensor does not name what it sees: nearest-neighbour association with
provisional landmarks, scored against the simulator's truth and against the ceiling.

Symbols used below:
  seif.preset_config("park", ...)      a car among 150 trees, a 30 m laser-like sensor
  config.clutter                       false detections per scan (Poisson)
  config.detection_probability         the chance a tree in range is reported
  seif.simulate(config) -> RobotLog    the world's records; build_dataset() makes filter steps
  seif.AssociationOptions              method (known, nn, jcbb), gates, provisional landmarks
  seif.Associator(options)             gives each observation a landmark id before the update
  seif.run_loop(filter, data, associate=...)   the run loop, with the associator's hook
  Observation.truth                    the simulator's id: the associator never reads it,
                                       the scoring does
  seif.association_ceiling(source, sensor)     what the true map seen from the true pose
                                       would associate right by likelihood: a reference

Run:  PYTHONPATH=build/python /usr/bin/python3 examples/python/unknown_association.py [steps]
"""
import sys

import seif

steps = int(sys.argv[1]) if len(sys.argv) > 1 else 600

# --- 1. The world: the park, one false detection per scan, one tree in ten missed. ------------
world = seif.preset_config("park", 0, steps, 1)
world.clutter = 1.0
world.detection_probability = 0.9
log = seif.simulate(world)
data = seif.build_dataset(log)

# --- 2. A filter with the world's noise, and an associator that hides the ids from it. --------
config = seif.paper_filter_config(world.noise)
slam = seif.make_filter("ekf", seif.start_pose(data), config)
options = seif.AssociationOptions()
options.method = "nn"  # each observation its nearest compatible landmark, greedily
# The defaults: accept inside chi2_2(0.99), start a landmark beyond chi2_2(0.9999), drop what
# falls between as ambiguous; a new landmark is provisional until seen 4 times in 20 scans.
associator = seif.Associator(options)

# --- 3. Run: before each update the associator names what each observation is of. -------------
seif.run_loop(slam, data, associate=lambda f, step, k, z: associator.associate(f, k, z))
associator.finish(slam)  # removes the landmarks never confirmed and scores the rest

# --- 4. How it did, against the truth and against what a perfect map would allow. -------------
counts = associator.counts
print(f"{counts.observations} observations, {counts.scored} with a truth id kept: "
      f"{100.0 * counts.correct / counts.scored:.2f} % associated right")
print(f"{counts.landmarks_final} landmarks at the end ({counts.spurious_landmarks} spurious, "
      f"{counts.duplicate_landmarks} duplicates); {counts.provisional_removed} provisional ones removed, "
      f"{counts.ambiguous_dropped} ambiguous observations dropped")
ceiling = seif.association_ceiling(seif.RobotLogSource(log, world.noise), config.sensor)
print(f"ceiling: {100.0 * ceiling.individual / ceiling.observations:.2f} % individually, "
      f"{100.0 * ceiling.joint / ceiling.observations:.2f} % jointly, of {ceiling.observations} labelled observations; "
      f"this run {100.0 * counts.correct / ceiling.observations:.2f} % of them")
# "associated right" above counts the observations the run kept; "of them" counts every
# labelled one, as the ceiling does (the difference: mostly those dropped as ambiguous).
