#pragma once
// Ctrl-C (SIGINT) or SIGTERM during a long command stops it at its next checkpoint (a run
// after the step it is in, a study after the runs or cases it finished), and what was
// finished is written. The handler stays for more of them (`timeout` and process managers
// send one to the process and one to its group); Ctrl-\ (SIGQUIT) still ends the process at
// once.
#include <atomic>

namespace seif::cli {

/// Installs the stop handler for SIGINT and SIGTERM while it lives, and restores what was
/// there. A signal the shell ignores (a background job's SIGINT, nohup) stays ignored.
class StopOnSignals {
 public:
  StopOnSignals();
  ~StopOnSignals();
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

  /// Set by the handler; for RunRequest::stop, ConsistencyOptions::stop, BenchRequest::stop,
  /// PaperRequest::stop.
  static const std::atomic<bool>* flag();

 private:
  using Handler = void (*)(int);
  Handler int_;
  Handler term_;
};

}  // namespace seif::cli
