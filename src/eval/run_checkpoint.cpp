#include "run_checkpoint.hpp"

#include "core/binary_archive.hpp"

#include <seif/core/errors.hpp>
#include <seif/filters/checkpoint.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace seif {

namespace {

void writeTrack(ArchiveWriter& w, const std::vector<TimedPose>& track) {
  w.count(track.size());
  for (const TimedPose& p : track) {
    w.f64(p.time);
    w.fixed(p.pose);
  }
}

/// Its stamps finite and in order, its poses finite: what a run writes, even where a
/// checkpoint's checksum was forged.
std::vector<TimedPose> readTrack(ArchiveReader& r, const char* what) {
  std::vector<TimedPose> track(r.count(what, 4 * 9));
  for (std::size_t k = 0; k < track.size(); ++k) {
    TimedPose& p = track[k];
    p.time = r.f64("time");
    if (!std::isfinite(p.time) || (k > 0 && p.time < track[k - 1].time)) {
      r.fail(std::string(what) + ": stamp " + std::to_string(k) + " is not finite or goes back in time");
    }
    r.fixed("pose", p.pose, true);
  }
  return track;
}

}  // namespace

void CheckpointWriter::afterUpdate(const SlamFilter& filter, const Step&, std::size_t k, double) {
  if (policy_.every > 0 && (k + 1) % policy_.every == 0) save(filter, k + 1);
}

void CheckpointWriter::save(const SlamFilter& filter, std::size_t steps) const {
  CheckpointExtras extras;
  extras.steps_consumed = steps;
  extras.values = policy_.values;
  extras.values[std::string(kRunOutputKey)] = encodeRunOutput(out_);
  if (associator_) extras.values[std::string(kAssociatorKey)] = associator_->saveState();
  if (associator_ && associator_->options().method != AssociationMethod::Known) {
    extras.values[std::string(kRunAssociationsKey)] = encodeRunAssociations(out_);
  }
  if (digest_) extras.values[std::string(kStepsDigestKey)] = std::to_string(digest_->value());
  saveCheckpoint(filter, policy_.path, extras);
}

std::string encodeRunOutput(const RunOutput& out) {
  ArchiveWriter w;
  w.section("run-output");
  w.u64(out.steps);
  writeTrack(w, out.trajectory);
  writeTrack(w, out.dead_reckoning);
  w.count(out.step_seconds.size());
  for (double s : out.step_seconds) w.f64(s);
  w.count(out.pose_covariances.size());
  for (const Mat3& P : out.pose_covariances) w.fixed(P);
  w.f64(out.seconds);
  w.u64(out.max_robot_links);
  w.u64(out.max_blocks_touched);
  return w.bytes();
}

RunOutput decodeRunOutput(std::string_view bytes, const std::string& name) {
  ArchiveReader r(bytes, name);
  r.section("run-output");
  RunOutput out;
  out.steps = static_cast<std::size_t>(r.u64("steps"));
  out.trajectory = readTrack(r, "trajectory poses");
  out.dead_reckoning = readTrack(r, "dead-reckoning poses");
  out.step_seconds.resize(r.count("step times", 9));
  for (double& s : out.step_seconds) {
    s = r.f64("step time");
    if (!(s >= 0.0 && std::isfinite(s))) r.fail("a step time is not a finite duration");
  }
  out.pose_covariances.resize(r.count("pose covariances", 9 * 9));
  for (Mat3& P : out.pose_covariances) r.fixed("pose covariance", P, true);
  out.seconds = r.f64("seconds");
  if (!(out.seconds >= 0.0 && std::isfinite(out.seconds))) r.fail("the run's time is not a finite duration");
  out.max_robot_links = static_cast<std::size_t>(r.u64("most robot links"));
  out.max_blocks_touched = static_cast<std::size_t>(r.u64("most blocks touched"));
  r.finish();
  if (out.trajectory.size() != out.steps + 1 || out.dead_reckoning.size() != out.steps + 1 ||
      out.step_seconds.size() != out.steps) {
    r.fail("the run's outputs do not match its " + std::to_string(out.steps) + " steps");
  }
  return out;
}

std::string encodeRunAssociations(const RunOutput& out) {
  ArchiveWriter w;
  w.section("run-associations");
  w.count(out.associations.size());
  for (const AssociationRecord& a : out.associations) {
    w.u64(a.step);
    w.u64(a.index);
    w.fixed(a.z);
    w.i64(a.truth);
    const ScanDecision& d = a.decision;
    w.u64(static_cast<std::uint64_t>(d.outcome) | (d.provisional ? 4u : 0u) | (d.applied ? 8u : 0u));
    w.i64(d.landmark);
    w.f64(d.d2);
  }
  w.count(out.merges.size());
  for (const MergeRecord& m : out.merges) {
    w.u64(m.step);
    w.i64(m.merge.kept);
    w.i64(m.merge.merged);
  }
  return w.bytes();
}

void decodeRunAssociations(std::string_view bytes, const std::string& name, RunOutput& out) {
  ArchiveReader r(bytes, name);
  r.section("run-associations");
  constexpr std::int64_t kIdMax = std::numeric_limits<int>::max();
  out.associations.resize(r.count("association records", 8 * 9));
  for (std::size_t i = 0; i < out.associations.size(); ++i) {
    AssociationRecord& a = out.associations[i];
    a.step = static_cast<std::size_t>(r.u64("association step"));
    a.index = static_cast<std::size_t>(r.u64("association index"));
    if (a.step >= out.steps || (i > 0 && a.step < out.associations[i - 1].step)) {
      r.fail("association record " + std::to_string(i) + ": step " + std::to_string(a.step) +
             " is out of order or beyond the run's " + std::to_string(out.steps) + " steps");
    }
    r.fixed("measurement", a.z, true);
    a.truth = static_cast<int>(r.i64In("truth id", kUnknownLandmark, kIdMax));
    ScanDecision& d = a.decision;
    const std::uint64_t flags = r.u64Max("decision", 15);
    if ((flags & 3u) > 2u) r.fail("association record " + std::to_string(i) + ": no such outcome");
    d.outcome = static_cast<ScanDecision::Outcome>(flags & 3u);
    d.provisional = (flags & 4u) != 0;
    d.applied = (flags & 8u) != 0;
    d.landmark = static_cast<int>(r.i64In("landmark id", kUnknownLandmark, kIdMax));
    if ((d.landmark == kUnknownLandmark) != (d.outcome == ScanDecision::Outcome::Ambiguous)) {
      r.fail("association record " + std::to_string(i) + ": its landmark does not match its outcome");
    }
    d.d2 = r.f64("d2");
    if (!(d.d2 >= 0.0)) r.fail("association record " + std::to_string(i) + ": d2 is not a distance");
  }
  out.merges.resize(r.count("merges", 3 * 9));
  for (MergeRecord& m : out.merges) {
    m.step = static_cast<std::size_t>(r.u64Max("merge step", out.steps));
    m.merge.kept = static_cast<int>(r.i64In("kept landmark", 0, kIdMax));
    m.merge.merged = static_cast<int>(r.i64In("merged landmark", 0, kIdMax));
  }
  r.finish();
}

RunResume runResumeFrom(const std::map<std::string, std::string>& values, std::size_t steps,
                        const std::string& checkpoint) {
  const auto it = values.find(std::string(kRunOutputKey));
  if (it == values.end()) {
    throw DataError(checkpoint, 0, "the checkpoint holds a filter but no run to resume (not written by seif run)");
  }
  RunResume resume;
  resume.steps = steps;
  resume.output = decodeRunOutput(it->second, checkpoint);
  if (resume.output.steps != steps) {
    throw DataError(checkpoint, 0, "the run's outputs hold " + std::to_string(resume.output.steps) + " steps, the filter " +
                                       std::to_string(steps));
  }
  if (const auto a = values.find(std::string(kAssociatorKey)); a != values.end()) resume.associator = a->second;
  if (const auto a = values.find(std::string(kRunAssociationsKey)); a != values.end()) {
    decodeRunAssociations(a->second, checkpoint, resume.output);
  } else if (!resume.associator.empty()) {
    resume.output.associations_from = steps;  // written before runs recorded them
  }
  // Checkpoints from before the digest carry none: their data is not checked.
  if (const auto d = values.find(std::string(kStepsDigestKey)); d != values.end()) {
    std::uint64_t v = 0;
    const char* end = d->second.data() + d->second.size();
    const auto [p, ec] = std::from_chars(d->second.data(), end, v);
    if (ec != std::errc() || p != end) throw DataError(checkpoint, 0, "the steps' digest '" + d->second + "' is not a number");
    resume.steps_digest = v;
  }
  return resume;
}

}  // namespace seif
