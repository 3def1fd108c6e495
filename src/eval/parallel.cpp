// The experiments' thread pool (include/seif/eval/parallel.hpp).
#include "eval/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace seif {

unsigned threadCount(unsigned requested, std::size_t tasks) {
  const unsigned wanted = requested > 0 ? requested : std::thread::hardware_concurrency();
  return std::max(1u, static_cast<unsigned>(std::min<std::size_t>(wanted, tasks)));
}

void parallelFor(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& task,
                 const std::function<void(std::size_t, std::size_t)>& done, const std::atomic<bool>* stop) {
  std::atomic<std::size_t> next{0};
  std::size_t finished = 0;
  std::mutex mutex;  // guards `finished`, `done` and `failure`
  std::exception_ptr failure;
  auto worker = [&] {
    for (std::size_t i = next++; i < count; i = next++) {
      if (stopRequested(stop)) return;
      try {
        task(i);
        const std::lock_guard<std::mutex> lock(mutex);
        ++finished;
        if (done) done(finished, count);  // it may throw too (a Python callback): the same path
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
        next = count;  // no new task starts
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threadCount(threads, count); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace seif
