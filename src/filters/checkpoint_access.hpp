#pragma once
// The filters' state in a checkpoint (docs/checkpoints.md): one writer and one reader per
// filter class, each in its own file (ekf_state.cpp, eif_state.cpp, seif_state.cpp), and
// the bookkeeping every filter shares (landmark index, first estimates, outlier gate) in
// small helpers of their own (bookkeeping_state.cpp). A friend of the classes it saves.
// A reader restores exactly what the writer wrote, in the same container order, and
// checks that the result is consistent (sizes, slots, links), so that a corrupted file
// whose checksum was forged still cannot make a later step read out of bounds.
#include "core/binary_archive.hpp"

#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include "filters/first_estimates.hpp"
#include "filters/landmark_book.hpp"
#include "filters/outlier_gate.hpp"
#include "filters/seif_slam.hpp"
#include "filters/seif_store.hpp"

#include <optional>
#include <unordered_map>
#include <vector>

namespace seif {

struct CheckpointAccess {
  // ---- shared bookkeeping (bookkeeping_state.cpp)
  static void writeIndex(ArchiveWriter& out, const std::vector<int>& ids);
  static void readIndex(ArchiveReader& in, std::vector<int>& ids, std::unordered_map<int, int>& slots);
  static void writeFirstEstimates(ArchiveWriter& out, const std::optional<FirstEstimates>& fej);
  /// `expected`: whether the filter's linearization has first estimates; `landmarks`: the map's size.
  static void readFirstEstimates(ArchiveReader& in, std::optional<FirstEstimates>& fej, bool expected, int landmarks);
  static void writeGate(ArchiveWriter& out, const OutlierGate& gate);
  static void readGate(ArchiveReader& in, OutlierGate& gate);
  /// The landmark book: the gate, the index and the first estimates, in that order.
  static void writeBook(ArchiveWriter& out, const LandmarkBook& book);
  static void readBook(ArchiveReader& in, LandmarkBook& book);

  // ---- the configuration a filter keeps (checkpoint.cpp)
  static const FilterConfig& config(const EkfSlam& f) { return f.config_; }
  static const FilterConfig& config(const EifSlam& f) { return f.config_; }
  static const FilterConfig& config(const SeifSlam& f) { return f.config_; }

  // ---- one filter each
  static void write(ArchiveWriter& out, const EkfSlam& f);   // ekf_state.cpp
  static void read(ArchiveReader& in, EkfSlam& f);
  static void write(ArchiveWriter& out, const EifSlam& f);   // eif_state.cpp
  static void read(ArchiveReader& in, EifSlam& f);
  static void write(ArchiveWriter& out, const SeifSlam& f);  // seif_state.cpp
  static void read(ArchiveReader& in, SeifSlam& f);
  static void write(ArchiveWriter& out, const SeifStore& s);
  static void read(ArchiveReader& in, SeifStore& s);
};

}  // namespace seif
