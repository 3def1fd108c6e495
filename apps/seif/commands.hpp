#pragma once
// The `seif` command-line tool: one function per sub-command, registered in commands.cpp.
namespace seif::cli {

/// Parses argv, runs the chosen sub-command, returns the process exit status:
/// 0 success, 1 usage error, 2 bad input data or numerical failure.
int main(int argc, char** argv);

}  // namespace seif::cli
