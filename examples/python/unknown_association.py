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
  seif.run_filter(filter, source, associator=...)   the same run streamed: it records every
                                       decision (RunOutput.associations) and merge
  seif.association_verdicts(out, filter, associator)  each recorded observation's verdict
                                       and its landmark at the end (seif run's associations.csv)

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

# --- 5. Each observation's fate: the same run streamed, every decision recorded. --------------
# run_filter gives the associator each scan as run_loop did, calls its finish(), and keeps a
# record per observation offered: the step, the measurement, its truth and the decision.
slam = seif.make_filter("ekf", seif.start_pose(data), config)
associator = seif.Associator(options)
out = seif.run_filter(slam, seif.RobotLogSource(log, world.noise), associator=associator)
verdicts, final = seif.association_verdicts(out, slam, associator)
V = seif.AssociationVerdict
print(f"recorded {len(out.associations)} observations: {verdicts.count(V.Correct)} correct, "
      f"{verdicts.count(V.Wrong)} wrong, {verdicts.count(V.Duplicate)} in a duplicate landmark")
wrong = [(r, at) for r, v, at in zip(out.associations, verdicts, final) if v == V.Wrong]
for r, at in wrong[:5]:  # whose tree each was, and whose the landmark it went to is
    # "new": it started the landmark (d2 to the nearest one), which more sightings of
    # another tree then labelled; "matched": inside that landmark's accept gate.
    how = r.decision.outcome.name.lower()
    print(f"  step {r.step}: tree {r.truth} at range {r.z[0]:.1f} m, {how} (d2 {r.decision.d2:.2f}), "
          f"is in landmark {at}, tree {associator.truth_of(at)}'s")
