// The SEIF allocates nothing in a step that adds no landmark and no link: its work
// buffers live on the stack or are reused. Counted by replacing the global operator new
// in this test binary (its own executable, see tests/CMakeLists.txt; the count is only
// read here).
//
// The whole replaceable family is replaced, every form on malloc/aligned_alloc + free:
// a partial replacement mixes allocators (e.g. std::stable_sort's temporary buffer comes
// from the nothrow form, which would otherwise be the library's -- under ASan, ASan's own
// -- while the plain delete that frees it is ours: an alloc-dealloc mismatch). Under ASan
// malloc and free are still intercepted, so the heap checks stay on.
#include "scenario.hpp"

#include "filters/seif_slam.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>

namespace {
std::atomic<std::size_t> g_allocations{0};

void* allocate(std::size_t size) noexcept {
  ++g_allocations;
  return std::malloc(size == 0 ? 1 : size);
}
void* allocate(std::size_t size, std::align_val_t alignment) noexcept {
  ++g_allocations;
  // aligned_alloc wants a size that is a multiple of the alignment (ASan checks it).
  const auto align = static_cast<std::size_t>(alignment);
  if (size > SIZE_MAX - align) return nullptr;
  return std::aligned_alloc(align, (std::max<std::size_t>(size, 1) + align - 1) / align * align);
}
void* allocateOrThrow(std::size_t size) {
  if (void* p = allocate(size)) return p;
  throw std::bad_alloc();
}
void* allocateOrThrow(std::size_t size, std::align_val_t alignment) {
  if (void* p = allocate(size, alignment)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return allocateOrThrow(size); }
void* operator new[](std::size_t size) { return allocateOrThrow(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocate(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocate(size); }
void* operator new(std::size_t size, std::align_val_t a) { return allocateOrThrow(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return allocateOrThrow(size, a); }
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate(size, a);
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate(size, a);
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

TEST(SeifAllocation, TheCounterSeesAllocations) {
  const std::size_t count = g_allocations.load();
  auto* v = new std::vector<double>(100);
  EXPECT_GE(g_allocations.load() - count, 2u);  // the vector and its buffer
  delete v;
}

TEST(SeifAllocation, TheCounterSeesEveryForm) {
  std::size_t count = g_allocations.load();
  std::vector<int> v(1000);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<int>((i * 7919) % 1000);
  count = g_allocations.load();
  std::stable_sort(v.begin(), v.end());  // a temporary buffer from the nothrow form
  EXPECT_GE(g_allocations.load() - count, 1u);
  EXPECT_TRUE(std::is_sorted(v.begin(), v.end()));

  count = g_allocations.load();
  void* plain = ::operator new[](24);
  void* nothrow = ::operator new(24, std::nothrow);
  void* aligned = ::operator new(100, std::align_val_t{64});
  void* aligned_nothrow = ::operator new[](100, std::align_val_t{128}, std::nothrow);
  EXPECT_EQ(g_allocations.load() - count, 4u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(aligned) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(aligned_nothrow) % 128, 0u);
  ::operator delete[](plain);
  ::operator delete(nothrow, std::nothrow);
  ::operator delete(aligned, 100, std::align_val_t{64});
  ::operator delete[](aligned_nothrow, std::align_val_t{128}, std::nothrow);
}

namespace {
// A small world seen over and over: after the first laps no landmark and few links are new.
// Returns the ESEIF relocalisations among the steps.
std::size_t expectNoHeapAllocationInSteadyStateSteps(const seif::SeifOptions& options,
                                                      seif::Linearization linearization = seif::Linearization::Standard,
                                                      int iterations = 1, std::size_t min_checked = 1000) {
  const seif::test::Scenario s = seif::test::makeScenario(31, 25, 1500);
  seif::FilterConfig config = seif::paperFilterConfig(s.noise);
  config.linearization = linearization;
  config.iterations = iterations;
  seif::SeifSlam seif(s.start, config, options);
  std::size_t checked = 0, allocating = 0;
  for (std::size_t k = 0; k < s.steps.size(); ++k) {
    const seif::Step& step = s.steps[k];
    const seif::FilterStats before = seif.stats();
    const std::size_t count = g_allocations.load();
    seif.step(step.u, step.observations);
    const std::size_t allocated = g_allocations.load() - count;
    const seif::FilterStats after = seif.stats();
    // New landmark-landmark links allocate; the ESEIF may create some in a step that drops
    // more robot links, so both counts are compared.
    const bool new_links = after.links > before.links ||
                           after.links - after.robot_links > before.links - before.robot_links;
    if (k < 100 || after.landmarks != before.landmarks || new_links) continue;
    ++checked;
    if (allocated > 0) ++allocating;
  }
  EXPECT_GT(checked, min_checked);
  EXPECT_EQ(allocating, 0u) << "of " << checked << " steady-state steps";
  return seif.eseifRelocalizations();
}
}  // namespace

TEST(SeifAllocation, NoHeapAllocationInSteadyStateSteps) { expectNoHeapAllocationInSteadyStateSteps({}); }

TEST(SeifAllocation, NoHeapAllocationInSteadyStateEseifSteps) {
  seif::SeifOptions options;
  options.sparsify = seif::SeifOptions::Sparsify::Eseif;
  options.active = 4;
  EXPECT_GT(expectNoHeapAllocationInSteadyStateSteps(options), 300u);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateInvariantIteratedSteps) {
  // Re-anchoring links the robot to re-anchored landmarks' neighbours: robot links, which
  // the stats count (those steps are left out like any step with a new link).
  seif::SeifOptions options;
  options.active = 12;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
  options.sparsify = seif::SeifOptions::Sparsify::Eseif;
  EXPECT_GT(expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700), 100u);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateDeferredMotionSteps) {
  // The held increment is a value in the filter: composing and flushing allocate nothing.
  seif::SeifOptions options;
  options.motion = seif::SeifOptions::Motion::Deferred;
  expectNoHeapAllocationInSteadyStateSteps(options);
  options.active = 12;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateStepsWithCovarianceBounds) {
  // The bounds' joint prior, tightening and re-anchoring run on fixed-capacity buffers.
  seif::SeifOptions options;
  options.bounds = true;
  expectNoHeapAllocationInSteadyStateSteps(options);
  options.active = 12;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateStepsWithRho) {
  // SeifOptions::rho scales the information by the one number kappa (informationScale()):
  // nothing in the store is rewritten, and nothing is allocated for it.
  seif::SeifOptions options;
  options.rho = 0.001;
  expectNoHeapAllocationInSteadyStateSteps(options);
  options.active = 12;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateStepsWithTheGaugeKept) {
  // SeifOptions::gauge = Kept corrects each sparsification on the gathered block, in
  // fixed-capacity matrices: standard, and invariant iterated with 12 active.
  seif::SeifOptions options;
  options.gauge = seif::SeifOptions::Gauge::Kept;
  expectNoHeapAllocationInSteadyStateSteps(options);
  options.active = 12;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateStepsWithTheCoarseLevel) {
  // SeifOptions::coarse = Rigid keeps its sums per changed row, its list of changed rows
  // reused from step to step: standard, and invariant iterated with 12 active, gauge kept.
  seif::SeifOptions options;
  options.coarse = seif::SeifOptions::Coarse::Rigid;
  expectNoHeapAllocationInSteadyStateSteps(options);
  options.active = 12;
  options.gauge = seif::SeifOptions::Gauge::Kept;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
}

TEST(SeifAllocation, NoHeapAllocationInSteadyStateStepsInTheWildfireOrder) {
  // RelaxOrder::Wildfire's queue and journal grow to their largest and are reused: the
  // consumed front is erased in place between steps.
  seif::SeifOptions options;
  options.relax_order = seif::SeifOptions::RelaxOrder::Wildfire;
  options.wildfire = 0.01;
  expectNoHeapAllocationInSteadyStateSteps(options);
  options.coarse = seif::SeifOptions::Coarse::Rigid;
  options.omega = 1.95;
  options.active = 12;
  options.gauge = seif::SeifOptions::Gauge::Kept;
  expectNoHeapAllocationInSteadyStateSteps(options, seif::Linearization::Invariant, 2, 700);
}

// Every marginal of a state comes from one factorisation: the first read factors H and
// computes the selected inverse's columns it needs, later reads compute the rest of their
// paths, and no read builds an N-row matrix (the landed getter solved with a dense
// (3+2N) x 2 right-hand side per landmark: one allocation each, O(N^2) for a map).
TEST(SeifAllocation, AllMarginalsOfAStateCostOneFactorisation) {
  const seif::test::Scenario s = seif::test::makeScenario(7, 600, 200, 4.0);
  seif::FilterConfig config = seif::paperFilterConfig(s.noise);
  seif::SeifSlam seif(s.start, config);
  for (const seif::Step& step : s.steps) seif.step(step.u, step.observations);
  ASSERT_GT(seif.landmarkIds().size(), 300u);
  double trace = 0.0;
  std::size_t count = g_allocations.load();
  trace += seif.poseCovariance().trace();
  for (int id : seif.landmarkIds()) trace += seif.landmarkCovariance(id).trace();
  const std::size_t first_pass = g_allocations.load() - count;
  count = g_allocations.load();
  for (int id : seif.landmarkIds()) trace += seif.landmarkCovariance(id).trace();
  const std::size_t second_pass = g_allocations.load() - count;
  EXPECT_GT(trace, 0.0);
  // A few dozen in the factorisation (triplets, ordering, symbolic analysis), whatever N.
  EXPECT_LT(first_pass, 100u) << "for " << seif.landmarkIds().size() << " landmarks";
  EXPECT_EQ(second_pass, 0u);
}

#include "association/candidate_grid.hpp"

// The associator's index: once every landmark is indexed and has a spread, a scan's work
// on it - new spreads (the largest among them dropping), moves within a cell, queries into a
// buffer that is large enough - allocates nothing.
TEST(SeifAllocation, TheCandidateGridsSpreadsAndQueriesAllocateNothing) {
  seif::CandidateGrid grid;
  grid.setCell(10.0);
  for (int id = 0; id < 200; ++id) {
    grid.put(id, seif::Vec2(1.0 + 0.5 * id, 2.0));
    grid.setSpread(id, 0.1 + 0.01 * id);
  }
  std::vector<int> out;
  out.reserve(200);
  const std::size_t count = g_allocations.load();
  for (int id = 0; id < 200; ++id) {
    grid.setSpread(id, id == 199 ? 0.05 : 0.2);  // the largest (id 199's 2.09) drops
    grid.put(id, seif::Vec2(1.0 + 0.5 * id + 0.001, 2.0));
    grid.query(seif::Vec2(50.0, 2.0), 1.0, 3.0, out);
  }
  EXPECT_EQ(g_allocations.load() - count, 0u);
  EXPECT_FALSE(out.empty());
}
