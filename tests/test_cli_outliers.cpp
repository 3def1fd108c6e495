// A gross outlier in real data: one 1e6 m range on MRCLAM robot 1 (dataset 6). Without a
// gate it gave exit 0 and an ATE of 1.6 km; now it is rejected, counted and harmless.
#include "cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;

const fs::path kMrclam = fs::path(SEIF_SHARED_DATA_DIR) / "mrclam" / "MRCLAM_Dataset6";

/// Copies robot 1 of dataset 6 and sets the range of one mid-run re-observation of a
/// landmark to 1e6 m.
seif::test::ScratchDir robotOneWithAnOutlier() {
  auto dir = scratchDir("outlier");  // returned: moved out
  for (const char* f : {"Barcodes.dat", "Landmark_Groundtruth.dat", "Robot1_Odometry.dat", "Robot1_Groundtruth.dat"}) {
    fs::copy_file(kMrclam / f, dir / f);
  }
  std::set<int> landmark_barcodes;
  {
    std::istringstream in(slurp(kMrclam / "Barcodes.dat"));
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      int subject = 0, barcode = 0;
      if (line.empty() || line[0] == '#' || !(fields >> subject >> barcode)) continue;
      if (subject > 5) landmark_barcodes.insert(barcode);
    }
  }
  std::istringstream in(slurp(kMrclam / "Robot1_Measurement.dat"));
  std::ofstream out(dir / "Robot1_Measurement.dat");
  std::map<int, int> seen;
  std::string line;
  int data_rows = 0;
  bool planted = false;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string time;
    int barcode = 0;
    double range = 0, bearing = 0;
    if (!line.empty() && line[0] != '#' && (fields >> time >> barcode >> range >> bearing)) {
      ++data_rows;
      if (!planted && data_rows > 900 && landmark_barcodes.count(barcode) && seen[barcode] > 3) {
        line = time + "\t" + std::to_string(barcode) + "\t1000000\t" + std::to_string(bearing);
        planted = true;
      }
      ++seen[barcode];
    }
    out << line << "\n";
  }
  EXPECT_TRUE(planted);
  return dir;
}

TEST(CliOutliers, AGrossRangeOutlierOnMrclamIsRejectedAndCounted) {
  if (!fs::exists(kMrclam)) GTEST_SKIP() << "MRCLAM dataset 6 not found at " << kMrclam;
  const auto data = robotOneWithAnOutlier();
  for (const char* filter : {"ekf", "seif"}) {
    SCOPED_TRACE(filter);
    const fs::path out = data / (std::string("out-") + filter);
    const auto r = runCli("run --dataset " + data.string() + " --robot 1 --filter " + filter + " --out " + out.string());
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("rejected 1 gross outlier observation"), std::string::npos) << r.out;
    const auto metrics = nlohmann::json::parse(slurp(out / "metrics.json"));
    EXPECT_EQ(metrics["rejected_observations"].get<int>(), 1);
    EXPECT_LT(metrics["ate_rmse"].get<double>(), 1.0);  // the README's clean runs: 0.24-0.46 m
  }
  // With the gate off the outlier goes in, as it did before the gate existed.
  const fs::path off = data / "out-off";
  const auto r = runCli("run --dataset " + data.string() + " --robot 1 --filter ekf --outlier-gate inf --out " + off.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto metrics = nlohmann::json::parse(slurp(off / "metrics.json"));
  EXPECT_EQ(metrics["rejected_observations"].get<int>(), 0);
  EXPECT_GT(metrics["ate_rmse"].get<double>(), 10.0);
  fs::remove_all(data);
}

}  // namespace
