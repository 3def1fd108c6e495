#pragma once
// The `seif` command-line tool. Each sub-command lives in its own cmd_<name>.cpp and is
// registered by main(); options shared by several commands live in options.hpp.
#include <CLI/CLI.hpp>

namespace seif::cli {

/// Parses argv, runs the chosen sub-command, returns the process exit status:
/// 0 success, 1 usage error, 2 bad input data or a numerical failure.
int main(int argc, char** argv);

/// The command line main() was called with, arguments joined by spaces.
const std::string& commandLine();

void addSimulateCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addPaperCommand(CLI::App& app);
void addConvertCommand(CLI::App& app);
void addConsistencyCommand(CLI::App& app);
void addPlotCommand(CLI::App& app);

}  // namespace seif::cli
