// Checkpoint I/O of the bookkeeping every filter shares: landmark index, first estimates,
// outlier gate (checkpoint_access.hpp).
#include "checkpoint_access.hpp"

#include <limits>
#include <string>

namespace seif {

void CheckpointAccess::writeIndex(ArchiveWriter& out, const LandmarkIndex& index) {
  out.section("landmark-index");
  out.count(index.ids().size());
  for (const int id : index.ids()) out.i64(id);
}

LandmarkIndex CheckpointAccess::readIndex(ArchiveReader& in) {
  in.section("landmark-index");
  const std::size_t n = in.count("landmark count", 9);
  LandmarkIndex index;
  for (std::size_t i = 0; i < n; ++i) {
    const auto id = static_cast<int>(in.i64In("landmark id", 0, std::numeric_limits<int>::max()));
    if (index.find(id) >= 0) in.fail("landmark id " + std::to_string(id) + " appears twice in the index");
    index.add(id);
  }
  return index;
}

void CheckpointAccess::writeFirstEstimates(ArchiveWriter& out, const std::optional<FirstEstimates>& fej) {
  out.section("first-estimates");
  out.u64(fej ? 1 : 0);
  if (!fej) return;
  out.fixed(fej->predictedPosition());
  out.count(static_cast<std::size_t>(fej->size()));
  for (int s = 0; s < fej->size(); ++s) out.fixed(fej->landmark(s));
}

void CheckpointAccess::readFirstEstimates(ArchiveReader& in, std::optional<FirstEstimates>& fej, bool expected,
                                          int landmarks) {
  in.section("first-estimates");
  const bool present = in.u64Max("first-estimates flag", 1) == 1;
  if (present != expected) {
    in.fail(present ? "first estimates stored for a filter without linearization=fej"
                    : "no first estimates stored for a filter with linearization=fej");
  }
  if (!present) {
    fej.reset();
    return;
  }
  Vec2 predicted;
  in.fixed("predicted position", predicted, true);
  fej.emplace(Pose2(predicted.x(), predicted.y(), 0.0));
  const std::size_t n = in.count("first-estimate count", 25);
  if (n != static_cast<std::size_t>(landmarks)) {
    in.fail(std::to_string(n) + " first estimates for " + std::to_string(landmarks) + " landmarks");
  }
  for (std::size_t i = 0; i < n; ++i) {
    Vec2 y;
    in.fixed("first estimate", y, true);
    fej->addLandmark(y);
  }
}

void CheckpointAccess::writeGate(ArchiveWriter& out, const OutlierGate& gate) {
  out.section("outlier-gate");
  out.u64(gate.rejected_);
}

void CheckpointAccess::readGate(ArchiveReader& in, OutlierGate& gate) {
  in.section("outlier-gate");
  gate.rejected_ = static_cast<std::size_t>(in.u64("rejected observations"));
}

void CheckpointAccess::writeBookkeeping(ArchiveWriter& out, const OutlierGate& gate, const LandmarkIndex& index,
                                        const std::optional<FirstEstimates>& fej) {
  writeGate(out, gate);
  writeIndex(out, index);
  writeFirstEstimates(out, fej);
}

void CheckpointAccess::readBookkeeping(ArchiveReader& in, OutlierGate& gate, LandmarkIndex& index,
                                       std::optional<FirstEstimates>& fej, const FilterConfig& config) {
  readGate(in, gate);
  index = readIndex(in);
  readFirstEstimates(in, fej, config.linearization == Linearization::FirstEstimates, index.size());
}

}  // namespace seif
