#include "commands.hpp"

#include <seif/core/errors.hpp>
#include <seif/core/version.hpp>

#include <cstdio>
#include <new>
#include <filesystem>
#include <stdexcept>

namespace seif::cli {

namespace {
std::string g_command_line;
}  // namespace

const std::string& commandLine() { return g_command_line; }

int main(int argc, char** argv) {
  g_command_line.clear();
  for (int i = 0; i < argc; ++i) g_command_line.append(i == 0 ? "seif" : " ").append(i == 0 ? "" : argv[i]);
  CLI::App app{
      "seif - SLAM with Sparse Extended Information Filters (Thrun et al. 2002).\n\n"
      "Typical use:\n"
      "  seif simulate --preset paper --seed 1 --out world       # a simulated dataset\n"
      "  seif run --dataset world --filter seif --out result      # run a filter on it\n"
      "  seif plot result                                         # draw it: result/map.png\n"
      "  seif run --dataset ../shared/data/mrclam/MRCLAM_Dataset6 --robot 3 --filter ekf --out r3\n"
      "  seif run --dataset ../shared/data/victoria-park --filter seif --out vp\n"
      "  seif run --dataset ../shared/data/victoria-park --detections raw --association jcbb \\\n"
      "           --filter seif:profile=consistent --out vp-raw     # ids unknown: associate\n"
      "  seif convert ../shared/data/victoria-park-isam/victoria_park.txt --to g2o --out vp.g2o\n"
      "  seif paper --runs 50 --out out/paper                     # the paper's experiment\n"
      "  seif consistency --preset paper --runs 50 --filters batch,ekf,seif --out out/nees\n"
      "  seif bench --filters ekf,seif --landmarks 100,1000 --out out/bench\n\n"
      "Datasets: MRCLAM, Victoria Park, iSAM and g2o (see README). Exit status: 0 success, 1 usage\n"
      "error, 2 bad input data or a numerical failure (one line on stderr names the cause), 130\n"
      "interrupted (Ctrl-C). Stopped or failed part-way, `seif run` first writes what it ran."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("seif ") + kVersion);
  addSimulateCommand(app);
  addRunCommand(app);
  addBenchCommand(app);
  addPaperCommand(app);
  addConvertCommand(app);
  addConsistencyCommand(app);
  addPlotCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  } catch (const Interrupted& e) {
    std::fprintf(stderr, "seif: %s\n", e.what());
    return 130;
  } catch (const DataError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const NumericError& e) {
    std::fprintf(stderr, "seif: numerical failure: %s\n", e.what());
    return 2;
  } catch (const ModelError& e) {
    std::fprintf(stderr, "seif: %s\n", e.what());
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    std::fprintf(stderr, "seif: %s\n", e.what());
    return 2;
  } catch (const InvalidArgument& e) {
    std::fprintf(stderr, "seif: %s\n", e.what());
    return 1;
  } catch (const Error& e) {
    std::fprintf(stderr, "seif: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "seif: out of memory (the run needs more than this machine has: a smaller "
                         "problem, or fewer runs at once with --jobs)\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "seif: error: %s\n", e.what());
    return 2;
  }
  return 0;
}

}  // namespace seif::cli
