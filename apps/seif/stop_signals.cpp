#include "stop_signals.hpp"

#include <csignal>

namespace seif::cli {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void requestStop(int) { g_stop.store(true, std::memory_order_relaxed); }

void (*install(int signal))(int) {
  const auto before = std::signal(signal, requestStop);
  if (before == SIG_IGN) std::signal(signal, SIG_IGN);
  return before;
}

}  // namespace

StopOnSignals::StopOnSignals() : int_(install(SIGINT)), term_(install(SIGTERM)) {}

StopOnSignals::~StopOnSignals() {
  std::signal(SIGINT, int_);
  std::signal(SIGTERM, term_);
}

const std::atomic<bool>* StopOnSignals::flag() { return &g_stop; }

}  // namespace seif::cli
