// The paper's world (Thrun et al. 2002, §4): 50 landmarks in the unit square, a robot on a
// lawnmower path, a short-range sensor. The same data through the EKF and the SEIF with
// the library's run loop, and their map errors against the truth.
//
// Symbols used (from <seif/seif.hpp>, namespace seif):
//   presetConfig, simulate, buildDataset   the simulator: a seeded world -> an in-memory Dataset
//   startPose                               where the filters start (the true start pose)
//   makeFilter, runFilter, RunOutput        a filter over every step of the dataset, timed
//   landmarkRmse                            RMS landmark error against the true map
#include <seif/seif.hpp>

#include <cstdio>
#include <memory>

int main() {
  using namespace seif;

  // The world and its log, all from one seed: bit-identical on every run.
  const WorldConfig world = presetConfig(WorldPreset::Paper, 0, 0, /*seed=*/1);
  const Dataset data = buildDataset(simulate(world));

  // The filters use the simulator's own noise, with the paper's models (a VelocityModel
  // with per-step noise and a RangeBearingModel).
  const FilterConfig config = paperFilterConfig(world.noise);

  bool ok = true;
  for (const char* spec : {"ekf", "seif"}) {
    std::unique_ptr<SlamFilter> filter = makeFilter(spec, startPose(data), config);
    const RunOutput out = runFilter(*filter, data);  // the one run loop: predict, update, observe
    const auto rmse = landmarkRmse(*filter, data.landmarks);
    std::printf("%-4s: %zu steps, %zu landmarks, landmark RMSE %.4f m, %.1f us/step, %zu links to the robot at most\n",
                spec, out.steps, filter->landmarkIds().size(), rmse ? *rmse : -1.0,
                1e6 * out.seconds / static_cast<double>(out.steps), out.max_robot_links);
    ok = ok && rmse && *rmse < 0.1;
  }
  std::printf("%s\n", ok ? "paper world: OK" : "paper world: an error is too large");
  return ok ? 0 : 1;
}
