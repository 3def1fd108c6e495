#pragma once
// The thread pool of the experiments (paper, consistency): independent runs, each stored
// by its index, so that results never depend on the number of threads; and the stop flag
// they, bench and the run loop read.
#include <atomic>
#include <cstddef>
#include <functional>

namespace seif {

/// The threads a study of `tasks` tasks uses: `requested`, or the number of cores when 0,
/// never more than the tasks and at least 1.
unsigned threadCount(unsigned requested, std::size_t tasks);

/// Whether `stop` (a run's or a study's flag, set from a signal handler or another thread;
/// none: never) is set.
inline bool stopRequested(const std::atomic<bool>* stop) {
  return stop != nullptr && stop->load(std::memory_order_relaxed);
}

/// Runs task(i) for every i in [0, count) on threadCount(threads, count) threads (the
/// calling one among them), taking the indices in order. `done(finished, count)` follows
/// every task that returned, one call at a time. The first exception a task or `done`
/// throws stops the others from starting new tasks and is rethrown here once all have
/// stopped. Once `stop` is set no task starts (those under way go on): the tasks that ran
/// are those `done` counted.
void parallelFor(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& task,
                 const std::function<void(std::size_t, std::size_t)>& done = {},
                 const std::atomic<bool>* stop = nullptr);

}  // namespace seif
