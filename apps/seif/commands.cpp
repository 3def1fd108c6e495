#include "commands.hpp"

#include <CLI/CLI.hpp>

namespace seif::cli {

int main(int argc, char** argv) {
  CLI::App app{"seif: SLAM with Sparse Extended Information Filters"};
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  return 0;
}

}  // namespace seif::cli
