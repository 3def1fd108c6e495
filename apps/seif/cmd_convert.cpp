// seif convert: a pose-graph dataset (iSAM or g2o) into the other format, so that g2o or
// GTSAM's batch solvers can run on the same data.
#include "commands.hpp"

#include <seif/io/graph_file.hpp>

#include <cstdio>

namespace seif::cli {

void addConvertCommand(CLI::App& app) {
  struct Args {
    std::string in, format = "auto", to, out;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Convert a pose-graph dataset between the iSAM/GTSAM text format (ODOMETRY, LANDMARK, BR)\n"
      "and g2o's 2-D format (VERTEX_SE2, VERTEX_XY, EDGE_SE2, EDGE_SE2_XY), keeping every id and\n"
      "number (covariances become information matrices and back). g2o output gets initial\n"
      "estimates from dead reckoning. The records must form one chain in time order.");
  cmd->add_option("IN", args->in, "input file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--format", args->format, "input format: auto, isam or g2o")
      ->check(CLI::IsMember({"auto", "isam", "g2o"}))
      ->capture_default_str();
  cmd->add_option("--to", args->to, "output format: g2o or isam")->required()->check(CLI::IsMember({"g2o", "isam"}));
  cmd->add_option("--out", args->out, "output file")->required();
  cmd->callback([args] {
    convertDataset(args->in, parseDatasetFormat(args->format), args->out, parseGraphFormat(args->to));
    std::printf("wrote %s (%s)\n", args->out.c_str(), args->to.c_str());
  });
}

}  // namespace seif::cli
