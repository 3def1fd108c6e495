// Checkpoint I/O of the bookkeeping every filter shares: landmark index, first estimates,
// outlier gate (checkpoint_access.hpp).
#include "checkpoint_access.hpp"

#include <limits>
#include <string>

namespace seif {

void CheckpointAccess::writeIndex(ArchiveWriter& out, const std::vector<int>& ids) {
  out.section("landmark-index");
  out.count(ids.size());
  for (const int id : ids) out.i64(id);
}

void CheckpointAccess::readIndex(ArchiveReader& in, std::vector<int>& ids, std::unordered_map<int, int>& slots) {
  in.section("landmark-index");
  const std::size_t n = in.count("landmark count", 9);
  ids.clear();
  slots.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const auto id = static_cast<int>(in.i64In("landmark id", 0, std::numeric_limits<int>::max()));
    if (!slots.emplace(id, static_cast<int>(i)).second) {
      in.fail("landmark id " + std::to_string(id) + " appears twice in the index");
    }
    ids.push_back(id);
  }
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
    in.fail(present ? "first estimates stored for a filter without linearization=fej or oc"
                    : "no first estimates stored for a filter with linearization=fej or oc");
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

void CheckpointAccess::writeBook(ArchiveWriter& out, const LandmarkBook& book) {
  writeGate(out, book.gate_);
  writeIndex(out, book.ids_);
  writeFirstEstimates(out, book.fej_);
}

void CheckpointAccess::readBook(ArchiveReader& in, LandmarkBook& book) {
  readGate(in, book.gate_);
  readIndex(in, book.ids_, book.slot_);
  readFirstEstimates(in, book.fej_, LandmarkBook::keepsFirstEstimates(book.linearization_), book.size());
}

}  // namespace seif
