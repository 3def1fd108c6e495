// seif simulate: writes a simulated world as an MRCLAM-layout dataset (robot 1) + meta.json.
#include "commands.hpp"
#include "options.hpp"

#include <seif/io/mrclam.hpp>
#include <seif/sim/world.hpp>

#include <climits>
#include <cstdio>

namespace seif::cli {
namespace {

struct SimulateArgs {
  std::string preset = "paper";
  std::string path = "lawnmower";
  int landmarks = 0;
  int steps = 0;
  std::uint64_t seed = 1;
  double clutter = 0.0;
  double detection_probability = 1.0;
  std::string out;
};

void simulateCommand(const SimulateArgs& args) {
  requireOutputFolder(args.out);
  WorldConfig config = presetConfig(parseWorldPreset(args.preset), args.landmarks, args.steps, args.seed);
  config.paper_path = parsePaperPath(args.path);
  config.clutter = args.clutter;
  config.detection_probability = args.detection_probability;
  SimStats stats;
  const RobotLog log = simulate(config, &stats);
  writeMrclam(args.out, log);
  std::printf("%s world: %d landmarks, %d steps, seed %llu, %.2f detections/step, %zu landmarks seen\n",
              args.preset.c_str(), config.landmarks, config.steps,
              static_cast<unsigned long long>(config.seed), stats.mean_detections_per_step,
              stats.distinct_landmarks_seen);
  if (config.clutter > 0.0 || config.detection_probability < 1.0) {
    std::printf("  %zu false detections (clutter, subject 0 in Barcodes.dat), %zu missed detections\n",
                stats.clutter, stats.missed_detections);
  }
  std::printf("  wrote %s (MRCLAM layout, robot 1, with meta.json)\n", args.out.c_str());
}

}  // namespace

void addSimulateCommand(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Simulate a robot in a landmark world and write the log in the UTIAS MRCLAM layout\n"
      "(Barcodes.dat, Landmark_Groundtruth.dat, Robot1_{Odometry,Measurement,Groundtruth}.dat)\n"
      "plus meta.json with the true noise, so `seif run` reads it like real data.\n"
      "Presets: paper (the paper's 50 landmarks in the unit square, 500 steps), uniform (the\n"
      "paper's density over N landmarks), corridor (a long strip: the map grows steadily), park\n"
      "(a car-like vehicle among trees, a laser-like sensor, Victoria Park's scale and noise).\n"
      "--clutter and --detection-probability add false and missed detections to any preset.\n"
      "See docs/simulator.md.");
  cmd->add_option("--preset", args->preset, "paper, uniform, corridor or park (an outdoor park at Victoria Park's scale)")
      ->check(CLI::IsMember({"paper", "uniform", "corridor", "park"}))
      ->capture_default_str();
  cmd->add_option("--path", args->path, "the paper world's path: lawnmower or lissajous")
      ->check(CLI::IsMember({"lawnmower", "lissajous"}))
      ->capture_default_str();
  cmd->add_option("--landmarks", args->landmarks, "number of landmarks (default: the preset's)")
      ->transform(integerIn(1, INT_MAX));
  cmd->add_option("--steps", args->steps, "number of control steps (default: the preset's)")
      ->transform(integerIn(1, INT_MAX));
  cmd->add_option("--seed", args->seed, "seed of all randomness")
      ->transform(seedValue())
      ->capture_default_str();
  addDetectionFlags(*cmd, args->clutter, args->detection_probability);
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->callback([args] { simulateCommand(*args); });
}

}  // namespace seif::cli
