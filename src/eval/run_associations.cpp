// A run's association records (RunOutput::associations): each observation's landmark at the
// end, its verdict against the truth, and associations.csv.
#include <seif/eval/run.hpp>

#include <seif/core/errors.hpp>
#include "core/files.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

namespace seif {

int mergedInto(int id, const std::vector<MergeRecord>& merges) {
  // Merges in order: a landmark kept by one may be merged by a later one, never the reverse
  // (a merged landmark is gone), so one pass follows the whole chain.
  for (const MergeRecord& m : merges) {
    if (m.merge.merged == id) id = m.merge.kept;
  }
  return id;
}

std::string_view associationVerdictName(AssociationVerdict v) {
  switch (v) {
    case AssociationVerdict::Unscored: return "";
    case AssociationVerdict::Correct: return "correct";
    case AssociationVerdict::Wrong: return "wrong";
    case AssociationVerdict::Duplicate: return "duplicate";
  }
  return "?";
}

namespace {

/// The landmark at the end of every landmark a record names (kUnknownLandmark: removed).
std::unordered_map<int, int> finalLandmarks(const RunOutput& out, const SlamFilter& filter) {
  std::unordered_map<int, int> final;
  for (const AssociationRecord& r : out.associations) {
    const int id = r.decision.landmark;
    if (id == kUnknownLandmark || final.count(id)) continue;
    const int at = mergedInto(id, out.merges);
    final[id] = filter.hasLandmark(at) ? at : kUnknownLandmark;
  }
  return final;
}

}  // namespace

std::vector<AssociationVerdict> associationVerdicts(const RunOutput& out, const SlamFilter& filter,
                                                    const Associator& associator, std::vector<int>* final_landmark) {
  const std::unordered_map<int, int> final = finalLandmarks(out, filter);
  std::vector<AssociationVerdict> verdicts(out.associations.size(), AssociationVerdict::Unscored);
  if (final_landmark) final_landmark->assign(out.associations.size(), kUnknownLandmark);
  for (std::size_t i = 0; i < out.associations.size(); ++i) {
    const AssociationRecord& r = out.associations[i];
    if (r.decision.landmark == kUnknownLandmark) continue;
    const int at = final.at(r.decision.landmark);
    if (final_landmark) (*final_landmark)[i] = at;
    if (at == kUnknownLandmark || r.truth < 0) continue;
    const int label = associator.truthOf(at);
    if (label != r.truth) {
      verdicts[i] = AssociationVerdict::Wrong;
    } else {
      verdicts[i] = associator.isDuplicate(at) ? AssociationVerdict::Duplicate : AssociationVerdict::Correct;
    }
  }
  return verdicts;
}

void writeAssociationsCsv(const std::filesystem::path& file, const RunOutput& out, const SlamFilter& filter,
                          const Associator& associator) {
  std::vector<int> final_landmark;
  const std::vector<AssociationVerdict> verdicts = associationVerdicts(out, filter, associator, &final_landmark);
  const auto id = [](int v) { return v == kUnknownLandmark ? std::string() : std::to_string(v); };
  AtomicFile f(file);
  std::fprintf(f.get(), "step,time,index,z0,z1,truth,outcome,landmark,d2,provisional,applied,final_landmark,label,verdict\n");
  for (std::size_t i = 0; i < out.associations.size(); ++i) {
    const AssociationRecord& r = out.associations[i];
    if (r.step + 1 >= out.trajectory.size()) {
      throw InvalidArgument("writeAssociationsCsv: a record of step " + std::to_string(r.step) + " in a run of " +
                            std::to_string(out.steps) + " steps");
    }
    const ScanDecision& d = r.decision;
    const int label = final_landmark[i] == kUnknownLandmark ? kUnknownLandmark : associator.truthOf(final_landmark[i]);
    char d2[32] = "inf";
    if (!std::isinf(d.d2)) std::snprintf(d2, sizeof d2, "%.6g", d.d2);
    std::fprintf(f.get(), "%zu,%.6f,%zu,%.9g,%.9g,%s,%s,%s,%s,%d,%d,%s,%s,%s\n", r.step, out.trajectory[r.step + 1].time,
                 r.index, r.z.x(), r.z.y(), id(r.truth).c_str(), std::string(scanOutcomeName(d.outcome)).c_str(),
                 id(d.landmark).c_str(), d2,
                 d.provisional ? 1 : 0, d.applied ? 1 : 0, id(final_landmark[i]).c_str(), id(label).c_str(),
                 std::string(associationVerdictName(verdicts[i])).c_str());
  }
  f.commit();
}

}  // namespace seif
