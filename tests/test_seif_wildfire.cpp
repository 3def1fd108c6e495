// The wildfire relaxation order (SeifOptions::RelaxOrder::Wildfire, filters/seif_relax_frontier.hpp):
// which landmarks it queues, that a step's changes to its queue are undone with the step, and
// that checkpoints and removals keep it exact.
#include "scenario.hpp"
#include <seif/core/errors.hpp>
#include <seif/filters/checkpoint.hpp>
#include <seif/filters/factory.hpp>
#include "filters/seif_relax_frontier.hpp"
#include "filters/seif_slam.hpp"
#include "filters/seif_store.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using seif::Mat2;
using seif::RelaxFrontier;
using seif::SeifStore;
using seif::Vec2;
using seif::Vec3;

// A chain of three landmarks, ids 10 - 11 - 12, each with H_ii = 4 I (conditional sigma 0.5).
SeifStore chain() {
  SeifStore store(seif::Mat3::Identity(), Vec3::Zero());
  for (int i = 0; i < 3; ++i) {
    const int slot = store.addLandmark(10 + i, Vec2(i, 0.0));
    Eigen::Matrix<double, 5, 5> H = Eigen::Matrix<double, 5, 5>::Zero();
    H.bottomRightCorner<2, 2>() = 4.0 * Mat2::Identity();
    store.addObservation(slot, H, Eigen::Matrix<double, 5, 1>::Zero());
  }
  store.addToLink(0, 1, -Mat2::Identity());
  store.addToLink(1, 2, -Mat2::Identity());
  return store;
}

Eigen::VectorXd meanWith(const SeifStore& store, int slot, const Vec2& mu) {
  Eigen::VectorXd m = store.mean();
  m.segment<2>(3 + 2 * slot) = mu;
  return m;
}

int slotOf(int id) { return id >= 10 && id <= 12 ? id - 10 : -1; }

TEST(RelaxFrontier, AMoveBeyondTheThresholdQueuesTheNeighboursOnce) {
  SeifStore store = chain();
  RelaxFrontier frontier(0.5, 10, 4);  // half a conditional sigma: 0.25 m here
  for (int s = 0; s < store.size(); ++s) frontier.addLandmark(store.node(s).mu);
  store.setMean(meanWith(store, 1, Vec2(1.2, 0.0)));  // 0.2 m: 0.4 sigma
  frontier.moved(store, 1);
  EXPECT_EQ(frontier.queued(), 0u);
  EXPECT_EQ(frontier.next(slotOf), -1);
  store.setMean(meanWith(store, 1, Vec2(1.3, 0.0)));  // 0.3 m from where it last spread: 0.6 sigma
  frontier.moved(store, 1);
  EXPECT_EQ(frontier.queued(), 2u);
  frontier.moved(store, 1);  // it spread from here: nothing new
  store.setMean(meanWith(store, 2, Vec2(2.0, 1.0)));
  frontier.moved(store, 2);  // its neighbour 1 is queued now; 2 is already
  EXPECT_EQ(frontier.queued(), 3u);
  EXPECT_EQ(frontier.next(slotOf), 0);  // first in, first out
  EXPECT_EQ(frontier.next(slotOf), 2);
  EXPECT_EQ(frontier.next(slotOf), 1);
  EXPECT_EQ(frontier.next(slotOf), -1);
  // Popped, a landmark can be queued again.
  store.setMean(meanWith(store, 1, Vec2(2.0, 0.0)));
  frontier.moved(store, 1);
  EXPECT_EQ(frontier.queued(), 2u);
}

TEST(RelaxFrontier, ASpreadQueuesTheNeighboursWhateverTheMove) {
  SeifStore store = chain();
  RelaxFrontier frontier(0.5, 10, 4);
  for (int s = 0; s < store.size(); ++s) frontier.addLandmark(store.node(s).mu);
  frontier.moved(store, 1);  // it has not moved
  EXPECT_EQ(frontier.queued(), 0u);
  frontier.spread(store, 1);
  EXPECT_EQ(frontier.queued(), 2u);
  EXPECT_EQ(frontier.next(slotOf), 0);
  EXPECT_EQ(frontier.next(slotOf), 2);
}

TEST(RelaxFrontier, ARemovedLandmarkIsSkippedAndTheMovedSlotKeepsItsState) {
  SeifStore store = chain();
  RelaxFrontier frontier(0.1, 10, 4);
  for (int s = 0; s < store.size(); ++s) frontier.addLandmark(store.node(s).mu);
  store.setMean(meanWith(store, 1, Vec2(1.0, 1.0)));
  frontier.moved(store, 1);  // queues 10 and 12
  ASSERT_EQ(frontier.queued(), 2u);
  // Landmark 10 (slot 0) goes; 12 moves from slot 2 into slot 0.
  frontier.removeSlot(0);
  auto after = [](int id) { return id == 12 ? 0 : id == 11 ? 1 : -1; };
  EXPECT_EQ(frontier.next(after), 0);  // 10 skipped; 12, now in slot 0
  EXPECT_EQ(frontier.next(after), -1);
  const RelaxFrontier::State st = frontier.state();
  ASSERT_EQ(st.spread_from.size(), 2u);
  EXPECT_EQ(st.spread_from[0], Vec2(2.0, 0.0));  // 12's, moved with it
  EXPECT_EQ(st.spread_from[1], Vec2(1.0, 1.0));  // 11 spread from here
  EXPECT_EQ(st.is_queued, (std::vector<unsigned char>{0, 0}));
}

TEST(RelaxFrontier, RollbackRestoresTheQueueAndTheSpreadPoints) {
  SeifStore store = chain();
  RelaxFrontier frontier(0.1, 10, 4);
  for (int s = 0; s < store.size(); ++s) frontier.addLandmark(store.node(s).mu);
  store.setMean(meanWith(store, 0, Vec2(0.0, 1.0)));
  frontier.moved(store, 0);  // queues 11
  frontier.begin();
  const RelaxFrontier::State before = frontier.state();
  EXPECT_EQ(frontier.next(slotOf), 1);
  store.setMean(meanWith(store, 1, Vec2(1.0, 1.0)));
  frontier.moved(store, 1);  // queues 10 and 12
  frontier.addLandmark(Vec2(5.0, 5.0));
  frontier.rollback();
  const RelaxFrontier::State after = frontier.state();
  EXPECT_EQ(after.queue, before.queue);
  EXPECT_EQ(after.spread_from, before.spread_from);
  EXPECT_EQ(after.is_queued, before.is_queued);
}

TEST(Wildfire, ARefusedStepLeavesItsQueueAsItWas) {
  // As ConservativeSparsification's refused step (test_conservative_sparsification.cpp): the
  // whole filter is as it was before the step, byte for byte in its checkpoint, which holds
  // the wildfire queue and every landmark's spread point (and, with either order, the
  // store's counters).
  const seif::test::Scenario s = seif::test::makeScenario(12, 40, 400);
  for (const auto order : {seif::SeifOptions::RelaxOrder::Cyclic, seif::SeifOptions::RelaxOrder::Wildfire}) {
    seif::SeifOptions o;
    o.active = 3;
    o.sparsify = seif::SeifOptions::Sparsify::Conservative;
    o.relax_order = order;
    o.wildfire = 0.01;
    seif::SeifSlam seif(s.start, seif::test::configFor(s), o);
    bool refused = false;
    std::size_t queued = 0;
    for (const seif::Step& step : s.steps) {
      seif.predict(step.u);
      const std::string bytes = seif::saveToBytes(seif);
      queued = seif.wildfireQueued();
      try {
        seif.update(step.observations);
      } catch (const seif::NumericError&) {
        EXPECT_TRUE(seif::saveToBytes(seif) == bytes) << "the refused step changed the filter";
        refused = true;
        break;
      }
    }
    ASSERT_TRUE(refused) << "the scenario was expected to refuse a step";
    if (order == seif::SeifOptions::RelaxOrder::Wildfire) {
      EXPECT_GT(queued, 0u) << "nothing was queued";
    }
  }
}

TEST(Wildfire, ACheckpointAfterARemovalResumesBitExactly) {
  // A removal runs outside a step and moves the last slot: the queue (ids) and the spread
  // points (slots) follow; a checkpoint after it resumes bit-exactly.
  const seif::test::Scenario s = seif::test::makeScenario(8, 30, 80);
  const std::string spec = "seif:profile=consistent,active=6,relax-order=wildfire,wildfire=0.01,relax=3";
  auto f = seif::makeFilter(spec, s.start, seif::test::configFor(s));
  auto twin = seif::makeFilter(spec, s.start, seif::test::configFor(s));
  for (std::size_t k = 0; k < 40; ++k) {
    f->step(s.steps[k].u, s.steps[k].observations);
    twin->step(s.steps[k].u, s.steps[k].observations);
  }
  ASSERT_GT(dynamic_cast<const seif::SeifSlam&>(*f).wildfireQueued(), 0u) << "nothing queued to resume";
  const int victim = f->landmarkIds()[3];
  f->removeLandmark(victim);
  twin->removeLandmark(victim);
  const std::string bytes = seif::saveToBytes(*f);
  auto resumed = seif::loadFromBytes(bytes, "memory");
  EXPECT_EQ(seif::saveToBytes(*resumed), bytes);
  for (std::size_t k = 40; k < s.steps.size(); ++k) {
    resumed->step(s.steps[k].u, s.steps[k].observations);
    twin->step(s.steps[k].u, s.steps[k].observations);
  }
  EXPECT_EQ(resumed->mean(), twin->mean());
}

TEST(Wildfire, AMergedLandmarksNeighboursAreQueued) {
  // A merge gives the kept landmark drop's neighbours and a new mean: every neighbour is
  // queued at once, even where no mean moved past the threshold (99 sigmas: none does here).
  const seif::test::Scenario s = seif::test::makeScenario(9, 30, 60);
  seif::SeifOptions o;
  o.relax_order = seif::SeifOptions::RelaxOrder::Wildfire;
  o.wildfire = 99.0;
  seif::SeifSlam seif(s.start, seif::test::configFor(s), o);
  for (const seif::Step& step : s.steps) seif.step(step.u, step.observations);
  const std::vector<int> ids = seif.landmarkIds();
  ASSERT_GE(ids.size(), 2u);
  ASSERT_EQ(seif.wildfireQueued(), 0u) << "a move spread: the threshold is too low for this test";
  seif.mergeLandmarks(ids[0], ids[1]);
  const SeifStore& store = seif.store();
  const int kept = [&] {
    for (int slot = 0; slot < store.size(); ++slot) {
      if (store.ids()[static_cast<std::size_t>(slot)] == ids[0]) return slot;
    }
    return -1;
  }();
  ASSERT_GE(kept, 0);
  EXPECT_GT(store.node(kept).links.size(), 0u);
  EXPECT_EQ(seif.wildfireQueued(), store.node(kept).links.size());
}

TEST(Wildfire, TheThresholdIsChecked) {
  const seif::test::Scenario s = seif::test::makeScenario(5, 10, 5);
  EXPECT_THROW(seif::makeFilter("seif:relax-order=wildfire,wildfire=0", s.start, seif::test::configFor(s)),
               seif::InvalidArgument);
  EXPECT_THROW(seif::makeFilter("seif:wildfire=-1", s.start, seif::test::configFor(s)), seif::InvalidArgument);
  seif::SeifOptions o;
  o.wildfire = 0.0;
  EXPECT_THROW(seif::SeifSlam(s.start, seif::test::configFor(s), o), seif::InvalidArgument);
}

}  // namespace
