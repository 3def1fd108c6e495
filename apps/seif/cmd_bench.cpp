#include "commands.hpp"

namespace seif::cli {
void addBenchCommand(CLI::App&) {}
}  // namespace seif::cli
