// seif plot: draws a `seif run` output folder (trajectory, map with 95 % covariance
// ellipses, dead reckoning, GPS fixes, ground truth and associations when the run stored them) into RUN_DIR/map.png with
// scripts/figures/run_map.py.
#include "commands.hpp"
#include "options.hpp"

#include <seif/core/errors.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace seif::cli {
namespace {

struct PlotArgs {
  std::string run_dir;
  std::string title;
};

void plot(const PlotArgs& args) {
  const std::filesystem::path dir(args.run_dir);
  for (const char* file : {"trajectory.tum", "map.csv"}) {
    if (!std::filesystem::is_regular_file(dir / file)) {
      throw DataError((dir / file).string(), 0, "missing: RUN_DIR must be the output folder of `seif run`");
    }
  }
  const std::filesystem::path png = dir / "map.png";
  std::vector<std::string> script_args = {png.string(), "--ellipses"};
  if (std::filesystem::is_regular_file(dir / "gps.csv")) script_args.insert(script_args.end(), {"--gps", (dir / "gps.csv").string()});
  if (!args.title.empty()) script_args.insert(script_args.end(), {"--title", args.title});
  script_args.push_back(dir.string());
  if (!renderFigure("run_map.py", script_args)) throw std::runtime_error("plot: " + png.string() + " was not drawn");
}

}  // namespace

void addPlotCommand(CLI::App& app) {
  auto args = std::make_shared<PlotArgs>();
  CLI::App* cmd = app.add_subcommand(
      "plot",
      "Draw the output folder of `seif run` into RUN_DIR/map.png: the trajectory, the map with\n"
      "each landmark's 95% covariance ellipse (when map.csv has covariances), the dead\n"
      "reckoning and, when the dataset had GPS (RUN_DIR/gps.csv), the fixes, with the\n"
      "trajectory and map rigidly aligned to them; else, when the dataset had ground truth\n"
      "(groundtruth.tum, landmarks_groundtruth.csv), the true path and landmarks, aligned to\n"
      "them the same way. With RUN_DIR/associations.csv (--association nn\n"
      "or jcbb), each observation scored wrong is a line from its pose to its landmark, and the\n"
      "duplicate and unlabelled landmarks are marked. Rendered by scripts/figures/run_map.py with\n"
      "/usr/bin/python3 and matplotlib.");
  cmd->add_option("RUN_DIR", args->run_dir, "output folder of `seif run`")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--title", args->title, "title of the figure");
  cmd->callback([args] { plot(*args); });
}

}  // namespace seif::cli
