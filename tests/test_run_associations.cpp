// A run's association records (RunOutput::associations, associations.csv): one per
// observation offered, each decision as the associator made it, each observation's landmark
// at the end through the merges, and verdicts that add up to the associator's own score.
#include "cli_support.hpp"

#include <seif/eval/run_dataset.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using seif::test::scratchDir;
using seif::test::slurp;

namespace {

using namespace seif;

/// associations.csv's rows, each as column name -> text.
std::vector<std::map<std::string, std::string>> readCsv(const fs::path& file) {
  std::istringstream in(slurp(file));
  const auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream s(line);
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
  };
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line);
    EXPECT_EQ(cells.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

/// Runs `request` into `out` and checks its records against its counts and its file.
/// Returns how many records a merge moved to another landmark.
std::size_t expectRecordsAddUp(const RunRequest& request, const fs::path& out) {
  fs::create_directories(out);
  const RunReport r = runDataset(request, out);
  EXPECT_FALSE(r.output.failure);
  const AssociationCounts& c = r.association.value();
  const std::vector<AssociationRecord>& records = r.output.associations;
  EXPECT_EQ(records.size(), c.observations);
  std::map<ScanDecision::Outcome, std::size_t> outcomes;
  for (std::size_t i = 0; i < records.size(); ++i) {
    ++outcomes[records[i].decision.outcome];
    EXPECT_LT(records[i].step, r.output.steps);
    if (i > 0 && records[i].step == records[i - 1].step) {
      EXPECT_EQ(records[i].index, records[i - 1].index + 1);
    }
  }
  EXPECT_EQ(outcomes[ScanDecision::Outcome::New], c.new_landmarks);
  EXPECT_EQ(outcomes[ScanDecision::Outcome::Ambiguous], c.ambiguous_dropped);
  EXPECT_EQ(r.output.merges.size(), c.merged);

  // The file says the same, row for row, and its verdicts are the associator's score.
  const auto rows = readCsv(out / "associations.csv");
  EXPECT_EQ(rows.size(), records.size());
  std::map<std::string, std::size_t> verdicts;
  std::size_t moved = 0;
  for (std::size_t i = 0; i < rows.size() && i < records.size(); ++i) {
    const auto& row = rows[i];
    const AssociationRecord& a = records[i];
    EXPECT_EQ(row.at("step"), std::to_string(a.step));
    EXPECT_EQ(row.at("outcome"), scanOutcomeName(a.decision.outcome));
    EXPECT_EQ(row.at("truth"), a.truth < 0 ? "" : std::to_string(a.truth));
    ++verdicts[row.at("verdict")];
    const std::string& final = row.at("final_landmark");
    if (final.empty()) continue;
    EXPECT_TRUE(r.output.associations[i].decision.landmark != kUnknownLandmark);
    const std::string& verdict = row.at("verdict");
    if (!verdict.empty()) {
      EXPECT_EQ(verdict == "wrong", row.at("label") != row.at("truth")) << "row " << i;
    }
    const int at = std::stoi(final);
    EXPECT_EQ(at, mergedInto(a.decision.landmark, r.output.merges));
    if (at != a.decision.landmark) ++moved;
  }
  EXPECT_EQ(verdicts["correct"], c.correct);
  EXPECT_EQ(verdicts["wrong"] + verdicts["duplicate"], c.wrong);
  EXPECT_EQ(verdicts["correct"] + verdicts["wrong"] + verdicts["duplicate"], c.scored);
  EXPECT_GT(c.correct, 0u);
  return moved;
}

}  // namespace

TEST(RunAssociations, MergesAreFollowedInOrder) {
  const std::vector<MergeRecord> merges = {{3, {1, 4}}, {5, {0, 1}}, {7, {2, 6}}};
  EXPECT_EQ(mergedInto(4, merges), 0);  // 4 -> 1 -> 0
  EXPECT_EQ(mergedInto(1, merges), 0);
  EXPECT_EQ(mergedInto(6, merges), 2);
  EXPECT_EQ(mergedInto(0, merges), 0);
  EXPECT_EQ(mergedInto(9, merges), 9);
}

// The park with clutter and missed detections, nn in the SEIF and jcbb in the EKF.
TEST(RunAssociations, EveryObservationIsRecordedAndTheVerdictsAreTheScore) {
  const auto dir = scratchDir("run-associations");
  WorldConfig world = presetConfig(WorldPreset::Park, 0, 1200, 2);
  world.clutter = 1.0;
  world.detection_probability = 0.9;
  const fs::path data = dir / "data";
  writeMrclam(data, simulate(world));
  RunRequest request;
  request.dataset = data;
  for (const auto& [filter, method] : {std::pair{"seif", AssociationMethod::NearestNeighbour},
                                       std::pair{"ekf", AssociationMethod::Jcbb}}) {
    SCOPED_TRACE(filter);
    request.filter = filter;
    request.association.method = method;
    expectRecordsAddUp(request, dir / filter);
  }
  // Known association records nothing and writes no file.
  request.association.method = AssociationMethod::Known;
  request.association.drop_unlabelled = true;
  fs::create_directories(dir / "known");
  const RunReport known = runDataset(request, dir / "known");
  EXPECT_TRUE(known.output.associations.empty());
  EXPECT_FALSE(fs::exists(dir / "known" / "associations.csv"));
}

// MRCLAM robot 3, whose duplicates the correspondence test merges: the merged landmarks'
// observations are scored in the landmark that kept them.
TEST(RunAssociations, MergedLandmarksObservationsAreInTheLandmarkKept) {
  const fs::path data = fs::path(SEIF_SHARED_DATA_DIR) / "mrclam" / "MRCLAM_Dataset6";
  if (!fs::exists(data)) GTEST_SKIP() << data << " is absent (../shared/data/README.md)";
  const auto dir = scratchDir("run-associations-mrclam");
  RunRequest request;
  request.dataset = data;
  request.dataset_options.robot = 3;
  request.filter = "seif:profile=consistent";
  request.association.method = AssociationMethod::NearestNeighbour;
  request.association.marginal = MarginalMode::Local;
  EXPECT_GT(expectRecordsAddUp(request, dir / "robot3"), 0u);
}
