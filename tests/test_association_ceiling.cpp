// The association ceiling (eval/association_ceiling.hpp) against closed forms: two landmarks
// on one ray, a range-only noise, so that each decision reduces to a one-dimensional
// comparison whose probability is a normal CDF.
#include <seif/core/errors.hpp>
#include <seif/eval/association_ceiling.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <filesystem>
#include <random>

namespace {

using namespace seif;

class EventList final : public EventSource {
 public:
  explicit EventList(DatasetInfo info) : info_(std::move(info)) {}
  void push(Event e) { events_.push_back(std::move(e)); }
  const DatasetInfo& info() const override { return info_; }
  bool next(Event& e) override {
    if (events_.empty()) return false;
    e = std::move(events_.front());
    events_.pop_front();
    return true;
  }
  double progress() const override { return 0.0; }

 private:
  DatasetInfo info_;
  std::deque<Event> events_;
};

constexpr double kSigma = 0.1;  // range noise; the bearing noise is negligible beside it
constexpr double kNear = 1.0, kFar = 1.1;  // two landmarks on the x axis, kSigma apart
constexpr int kA = 7, kB = 8;

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// `scans` instants at which the robot, at the origin, sees A alone (or A and B).
EventList twoOnARay(int scans, bool both, std::uint64_t seed) {
  DatasetInfo info;
  info.landmarks = {{kA, Vec2(kNear, 0.0)}, {kB, Vec2(kFar, 0.0)}};
  info.has_groundtruth = true;
  EventList source(info);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, kSigma);
  source.push(TimedPose{0.0, Pose2::Zero()});
  for (int k = 1; k <= scans; ++k) {
    ObservationEvent o{double(k), {}};
    o.observations.push_back(Observation{kUnknownLandmark, Vec2(kNear + n(rng), 0.0), std::nullopt, kA});
    if (both) o.observations.push_back(Observation{kUnknownLandmark, Vec2(kFar + n(rng), 0.0), std::nullopt, kB});
    source.push(o);
  }
  source.push(TimedPose{double(scans + 1), Pose2::Zero()});
  return source;
}

// Within 4.5 binomial standard deviations of p.
void expectFraction(std::size_t hits, std::size_t n, double p) {
  const double sd = std::sqrt(p * (1.0 - p) / double(n));
  EXPECT_NEAR(double(hits) / double(n), p, 4.5 * sd) << hits << " of " << n;
}

const RangeBearingModel kSensor(kSigma, 1e-6);

TEST(AssociationCeiling, OneObservationIsRightWhenItsErrorStaysOnItsSideOfTheMidpoint) {
  EventList source = twoOnARay(20000, /*both=*/false, 1);
  const auto c = associationCeiling(source, kSensor);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->observations, 20000u);
  EXPECT_EQ(c->scans, 20000u);
  // Right when z < (near + far) / 2: Φ(d / 2σ) = Φ(0.5).
  expectFraction(c->individual, c->observations, normalCdf(0.5));
  EXPECT_EQ(c->joint, c->individual);  // one observation per scan: nothing to share
  EXPECT_EQ(c->joint_truncated, 0u);
}

TEST(AssociationCeiling, TheJointAssignmentUsesThatEachLandmarkIsSeenOnce) {
  EventList source = twoOnARay(20000, /*both=*/true, 2);
  const auto c = associationCeiling(source, kSensor);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->observations, 40000u);
  // Individually each is right with Φ(d / 2σ); jointly the pair is swapped only when
  // e_A − e_B > d, so each is right with Φ(d / (σ√2)).
  expectFraction(c->individual, c->observations, normalCdf(0.5));
  expectFraction(c->joint, c->observations, normalCdf(1.0 / std::sqrt(2.0)));
  EXPECT_GT(c->joint, c->individual);
}

TEST(AssociationCeiling, LeavesOutClutterAndInstantsOutsideTheTrack) {
  DatasetInfo info;
  info.landmarks = {{kA, Vec2(kNear, 0.0)}};
  info.has_groundtruth = true;
  EventList source(info);
  source.push(ObservationEvent{0.5, {Observation{kUnknownLandmark, Vec2(kNear, 0.0), std::nullopt, kA}}});  // before
  source.push(TimedPose{1.0, Pose2::Zero()});
  source.push(ObservationEvent{1.5, {Observation{kUnknownLandmark, Vec2(kNear, 0.0), std::nullopt, kA},
                                     Observation{kUnknownLandmark, Vec2(0.5, 0.3), std::nullopt, kUnknownLandmark},
                                     Observation{kUnknownLandmark, Vec2(0.5, 0.3), std::nullopt, 99}}});  // 99: no such landmark
  source.push(TimedPose{2.0, Pose2::Zero()});
  const auto c = associationCeiling(source, kSensor);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->observations, 1u);
  EXPECT_EQ(c->individual, 1u);
  EXPECT_EQ(c->joint, 1u);
}

TEST(AssociationCeiling, NeedsGroundTruth) {
  DatasetInfo info;
  info.landmarks = {{kA, Vec2(kNear, 0.0)}};
  EventList no_track(info);
  no_track.push(ObservationEvent{1.0, {Observation{kUnknownLandmark, Vec2(kNear, 0.0), std::nullopt, kA}}});
  EXPECT_FALSE(associationCeiling(no_track, kSensor));
  EventList no_map(DatasetInfo{});
  no_map.push(TimedPose{1.0, Pose2::Zero()});
  EXPECT_FALSE(associationCeiling(no_map, kSensor));
  EventList any(DatasetInfo{});
  AssociationCeilingOptions bad;
  bad.gate = 0.0;
  EXPECT_THROW(associationCeiling(any, kSensor, bad), InvalidArgument);
}

TEST(AssociationCeiling, ANodeBoundStopsTheSearchAndCountsTheScan) {
  // Eight observations of eight landmarks a hair apart: every pairing is inside the gate.
  DatasetInfo info;
  ObservationEvent o{1.0, {}};
  for (int j = 0; j < 8; ++j) {
    info.landmarks[j] = Vec2(1.0 + 1e-3 * j, 0.0);
    o.observations.push_back(Observation{kUnknownLandmark, Vec2(1.0 + 1e-3 * j, 0.0), std::nullopt, j});
  }
  info.has_groundtruth = true;
  EventList crowded(info);
  crowded.push(TimedPose{0.0, Pose2::Zero()});
  crowded.push(o);
  crowded.push(TimedPose{2.0, Pose2::Zero()});
  AssociationCeilingOptions few;
  few.max_nodes = 4;  // the first path down the tree needs 9 nodes: none is complete
  const auto c = associationCeiling(crowded, kSensor, few);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->joint_truncated, 1u);
  EXPECT_EQ(c->observations, 8u);
  EXPECT_EQ(c->individual, 8u);  // noiseless: each is nearest its own
  EXPECT_EQ(c->joint, 0u);       // no assignment was found within the bound
}

// Through `seif run`'s library call: a simulated park with clutter, whose ceiling is near 1,
// and the same world at the paper's density, whose is not.
TEST(AssociationCeiling, ReportedByRunDatasetForSimulatedWorlds) {
  const auto dir = std::filesystem::temp_directory_path() / "seif_ceiling_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "out");
  auto fraction = [&](WorldPreset preset, int landmarks, int steps) {
    WorldConfig w = presetConfig(preset, landmarks, steps, 1);
    w.clutter = 1.0;
    w.detection_probability = 0.9;
    writeMrclam(dir / "log", simulate(w));
    RunRequest r;
    r.dataset = dir / "log";
    r.filter = "ekf";
    r.association.method = AssociationMethod::NearestNeighbour;
    const RunReport report = runDataset(r, dir / "out");
    EXPECT_TRUE(report.association_ceiling);
    const AssociationCeiling& c = *report.association_ceiling;
    EXPECT_GT(c.observations, 0u);
    EXPECT_GE(c.joint + c.observations / 100, c.individual);  // the joint test is rarely worse
    EXPECT_LE(report.association->correct, c.observations);   // the same labelled observations
    return double(c.individual) / double(c.observations);
  };
  EXPECT_GT(fraction(WorldPreset::Park, 0, 400), 0.99);
  EXPECT_LT(fraction(WorldPreset::Uniform, 200, 400), 0.95);
  std::filesystem::remove_all(dir);
}

}  // namespace
