// seif run: one filter over one dataset; writes trajectory.tum, map.csv, metrics.json.
#include "commands.hpp"
#include "options.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/io/results.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace seif::cli {
namespace {

struct RunArgs {
  std::string dataset;
  int robot = 1;
  std::string filter = "seif";
  std::string out = "out/run";
  NoiseFlags noise;
  SeifFlags seif;
  double outlier_gate = FilterConfig{}.outlier_gate;
};

nlohmann::json optionalJson(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

void run(const RunArgs& args) {
  requireOutputFolder(args.out);  // before any work: a bad --out fails at once
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  const auto read_start = Clock::now();
  const RobotLog log = readMrclam(args.dataset, args.robot);
  const Dataset data = buildDataset(log);
  if (data.steps.empty()) {
    throw DataError(args.dataset, 0, "robot " + std::to_string(args.robot) + " has no odometry to run");
  }
  const double read_seconds = seconds_since(read_start);
  FilterConfig config;
  config.noise = args.noise.resolve(data.noise);
  config.outlier_gate = args.outlier_gate;
  const SeifOptions seif_options = args.seif.resolve();
  const Pose2 start = startPose(data);
  auto filter = makeFilter(args.filter, start, config, seif_options);

  RunOutput out;
  {
    Progress progress("seif run " + args.filter);
    out = runFilter(*filter, data, std::ref(progress));
  }
  const auto dr = deadReckoning(data, start, filter->motionModel());
  // ATE and map errors after the best rigid alignment (as the TUM benchmark and evo define
  // ATE), and in the ground truth's frame as they are (the filter starts at the true pose).
  const auto ate = ateRmse(out.trajectory, data.groundtruth, Alignment::Rigid);
  const auto dr_ate = ateRmse(dr, data.groundtruth, Alignment::Rigid);
  const auto map_rmse = landmarkRmse(*filter, data.landmarks, Alignment::Rigid);
  const auto ate_raw = ateRmse(out.trajectory, data.groundtruth);
  const auto dr_ate_raw = ateRmse(dr, data.groundtruth);
  const auto map_rmse_raw = landmarkRmse(*filter, data.landmarks);

  const std::filesystem::path dir(args.out);
  std::filesystem::create_directories(dir);
  const auto write_start = Clock::now();
  writeTum(dir / "trajectory.tum", out.trajectory);
  writeMapCsv(dir / "map.csv", *filter);  // the marginal covariances are computed here
  const double write_seconds = seconds_since(write_start);
  std::vector<double> sorted = out.step_seconds;
  std::sort(sorted.begin(), sorted.end());
  const double median_us = sorted.empty() ? 0.0 : 1e6 * sorted[sorted.size() / 2];
  nlohmann::json metrics = {
      {"dataset", args.dataset},
      {"robot", args.robot},
      {"filter", args.filter},
      {"noise", toJson(config.noise)},
      {"steps", data.steps.size()},
      {"landmarks", filter->landmarkIds().size()},
      {"seconds", out.seconds},
      {"seconds_read", read_seconds},
      {"seconds_trajectory_and_map", write_seconds},
      {"us_per_step", data.steps.empty() ? 0.0 : 1e6 * out.seconds / static_cast<double>(data.steps.size())},
      {"us_per_step_median", median_us},
      {"links", out.final_stats.links},
      {"robot_links", out.final_stats.robot_links},
      {"max_robot_links", out.max_robot_links},
      {"max_landmark_links", out.final_stats.max_landmark_links},
      {"max_blocks_touched", out.max_blocks_touched},
      {"rejected_observations", out.rejected_observations},
      {"outlier_gate_sigmas", std::isinf(config.outlier_gate) ? nlohmann::json(nullptr) : nlohmann::json(config.outlier_gate)},
      {"landmark_rmse", optionalJson(map_rmse)},
      {"ate_rmse", optionalJson(ate)},
      {"dead_reckoning_ate_rmse", optionalJson(dr_ate)},
      {"landmark_rmse_unaligned", optionalJson(map_rmse_raw)},
      {"ate_rmse_unaligned", optionalJson(ate_raw)},
      {"dead_reckoning_ate_rmse_unaligned", optionalJson(dr_ate_raw)},
      {"errors", "*_rmse: after the best rigid 2-D alignment to ground truth; *_unaligned: as estimated, "
                 "in the ground truth's frame (the filter starts at the true pose)"},
      {"dropped", {{"robot_measurements", log.dropped.robot_measurements},
                   {"unknown_barcodes", log.dropped.unknown_barcodes},
                   {"before_first_control", data.dropped.before_first_control}}},
  };
  if (args.filter == "seif") metrics["seif"] = toJson(seif_options);
  writeJson((dir / "metrics.json").string(), metrics);

  auto fmt = [](const std::optional<double>& v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4f", v.value_or(std::nan("")));
    return v ? std::string(buf) : std::string("n/a");
  };
  std::printf("%s on %s (robot %d): %zu steps, %zu landmarks, %.1f us/step\n", args.filter.c_str(),
              args.dataset.c_str(), args.robot, data.steps.size(), filter->landmarkIds().size(),
              metrics["us_per_step"].get<double>());
  std::printf("  aligned:   landmark RMSE %s m | ATE %s m | dead-reckoning ATE %s m\n",
              fmt(map_rmse).c_str(), fmt(ate).c_str(), fmt(dr_ate).c_str());
  std::printf("  unaligned: landmark RMSE %s m | ATE %s m | dead-reckoning ATE %s m | links %zu\n",
              fmt(map_rmse_raw).c_str(), fmt(ate_raw).c_str(), fmt(dr_ate_raw).c_str(),
              out.final_stats.links);
  std::printf("  time: read %.2f s | filter %.2f s | trajectory and map with covariances %.2f s\n",
              read_seconds, out.seconds, write_seconds);
  if (out.rejected_observations > 0) {
    std::printf("  rejected %zu gross outlier observation%s (beyond %g sigma of the measurement noise)\n",
                out.rejected_observations, out.rejected_observations == 1 ? "" : "s", config.outlier_gate);
  }
  std::printf("  wrote %s/{trajectory.tum,map.csv,metrics.json}\n", args.out.c_str());
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run a SLAM filter over a dataset in the MRCLAM layout (real or from `seif simulate`).\n"
      "Writes OUT/trajectory.tum (TUM: t x y z qx qy qz qw), OUT/map.csv (id,x,y and the 2x2\n"
      "covariance) and OUT/metrics.json (timing, links, landmark RMSE, ATE and dead-reckoning\n"
      "ATE against ground truth when the dataset has it, else null). Noise defaults come\n"
      "from the dataset's meta.json, else the MRCLAM values documented in the README.");
  cmd->add_option("--dataset", args->dataset, "dataset folder (MRCLAM layout)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--robot", args->robot, "robot number in the dataset")
      ->transform(integerIn(1, 5))
      ->capture_default_str();
  cmd->add_option("--filter", args->filter, "ekf (dense covariance), eif (dense information) or seif")
      ->check(CLI::IsMember({"ekf", "eif", "seif"}))
      ->capture_default_str();
  cmd->add_option("--out", args->out, "output folder")->capture_default_str();
  cmd->add_option("--outlier-gate", args->outlier_gate,
                  "reject an observation whose innovation exceeds this many measurement standard "
                  "deviations (a gross outlier; counted in metrics.json rejected_observations); "
                  "'inf' disables the gate")
      ->check([](const std::string& s) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(s, v) || !(v > 0.0)) return "must be > 0 (or inf), found " + s;
        return {};
      })
      ->capture_default_str();
  args->noise.add(*cmd);
  args->seif.add(*cmd);
  cmd->callback([args] { run(*args); });
}

}  // namespace seif::cli
