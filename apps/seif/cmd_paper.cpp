#include "commands.hpp"

namespace seif::cli {
void addPaperCommand(CLI::App&) {}
}  // namespace seif::cli
