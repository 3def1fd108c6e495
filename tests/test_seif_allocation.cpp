// The SEIF allocates nothing in a step that adds no landmark and no link: its work
// buffers live on the stack or are reused. Counted by replacing the global operator new
// in this test binary (the count is only read here).
#include "scenario.hpp"

#include <seif/filters/seif_slam.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

namespace {
std::atomic<std::size_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

TEST(SeifAllocation, TheCounterSeesAllocations) {
  const std::size_t count = g_allocations.load();
  auto* v = new std::vector<double>(100);
  EXPECT_GE(g_allocations.load() - count, 2u);  // the vector and its buffer
  delete v;
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateSteps) {
  // A small world seen over and over: after the first laps no landmark and few links are new.
  const seif::test::Scenario s = seif::test::makeScenario(31, 25, 1500);
  seif::FilterConfig config;
  config.noise = s.noise;
  seif::SeifSlam seif(s.start, config);
  std::size_t checked = 0, allocating = 0;
  for (std::size_t k = 0; k < s.steps.size(); ++k) {
    const seif::Step& step = s.steps[k];
    const seif::FilterStats before = seif.stats();
    const std::size_t count = g_allocations.load();
    seif.step(step.u, step.observations);
    const std::size_t allocated = g_allocations.load() - count;
    const seif::FilterStats after = seif.stats();
    if (k < 100 || after.landmarks != before.landmarks || after.links > before.links) continue;
    ++checked;
    if (allocated > 0) ++allocating;
  }
  EXPECT_GT(checked, 1000u);
  EXPECT_EQ(allocating, 0u) << "of " << checked << " steady-state steps";
}
