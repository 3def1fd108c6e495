// `seif run` and `seif convert` end to end on every dataset format: what a user runs, what
// they get back (outputs, figures in metrics.json, exit status 2 with file:line on bad data).
#include "cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;
const std::string kData = SEIF_SHARED_DATA_DIR;

std::size_t lines(const fs::path& file) {
  std::ifstream in(file);
  std::size_t n = 0;
  std::string l;
  while (std::getline(in, l)) n += !l.empty() && l[0] != '#';
  return n;
}

TEST(CliDatasets, VictoriaParkSeifBeatsDeadReckoningAgainstGps) {
  const std::string vp = kData + "/victoria-park";
  if (!fs::exists(vp + "/controls.txt")) GTEST_SKIP() << "Victoria Park not found at " << vp;
  const auto dir = scratchDir("vp");
  const auto r = runCli("run --dataset " + vp + " --filter seif --out " + dir.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("noise sigma_speed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(default for victoria-park)"), std::string::npos) << r.out;
  const auto m = nlohmann::json::parse(slurp(dir / "metrics.json"));
  EXPECT_EQ(m["format"], "victoria-park");
  EXPECT_EQ(m["landmarks"], 299);
  EXPECT_GT(m["gps_fixes"].get<int>(), 4400);
  EXPECT_LE(m["gps_rmse"].get<double>(), 3.0);
  EXPECT_LT(10.0 * m["gps_rmse"].get<double>(), m["dead_reckoning_gps_rmse"].get<double>());
  // One fix jumps 141 m in 2.2 s (t = 1244.25 s); without it the RMSE is much smaller.
  EXPECT_EQ(m["gps_jumps"], 1);
  EXPECT_EQ(m["information_scale"], 1.0);  // the paper's sparsification does not scale
  EXPECT_LT(m["gps_rmse_without_jumps"].get<double>(), m["gps_rmse"].get<double>() - 0.5);
  EXPECT_NE(r.out.find("without the 1 that jump"), std::string::npos) << r.out;
  EXPECT_TRUE(m["ate_rmse"].is_null());  // no ground truth
  EXPECT_FALSE(m["version"].get<std::string>().empty());
  EXPECT_NE(m["command_line"].get<std::string>().find("--filter seif"), std::string::npos);
  EXPECT_NE(m["start_pose_source"].get<std::string>().find("origin"), std::string::npos);
  for (const char* f : {"trajectory.tum", "dead_reckoning.tum", "map.csv"}) EXPECT_GT(lines(dir / f), 200u) << f;
  fs::remove_all(dir);
}

TEST(CliDatasets, IsamGraphWithEveryFilterAndThroughG2o) {
  const std::string isam = kData + "/victoria-park-isam/victoria_park.txt";
  if (!fs::exists(isam)) GTEST_SKIP() << "victoria_park.txt not found at " << isam;
  const auto dir = scratchDir("isam");
  for (const char* f : {"ekf", "eif", "seif"}) {
    const auto r = runCli("run --dataset " + isam + " --filter " + f + " --trajectory-covariance on --out " +
                          (dir / f).string());
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(lines(dir / f / "trajectory.tum"), 6969u) << f;
    EXPECT_EQ(lines(dir / f / "trajectory_cov.csv"), 6970u) << f;  // header + one row per pose
    EXPECT_EQ(lines(dir / f / "map.csv"), 152u) << f;  // header + 151 landmarks
    // The noise is each record's: no one value.
    EXPECT_NE(r.out.find("noise odometry covariance per record"), std::string::npos) << r.out;
    for (const auto& n : nlohmann::json::parse(slurp(dir / f / "metrics.json")).at("noise")) {
      EXPECT_TRUE(n.at("value").is_null()) << n;
    }
  }
  ASSERT_EQ(runCli("convert " + isam + " --to g2o --out " + (dir / "vp.g2o").string()).status, 0);
  ASSERT_EQ(runCli("convert " + (dir / "vp.g2o").string() + " --to isam --out " + (dir / "vp.txt").string()).status, 0);
  const auto r = runCli("run --dataset " + (dir / "vp.g2o").string() + " --filter seif --out " + (dir / "g2o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(dir / "g2o" / "trajectory.tum"), slurp(dir / "seif" / "trajectory.tum"));
  EXPECT_EQ(slurp(dir / "g2o" / "map.csv"), slurp(dir / "seif" / "map.csv"));
  fs::remove_all(dir);
}

TEST(CliDatasets, BatchOnTheIsamGraphReachesGtsamsOptimumFromAFilter) {
  // GTSAM's Levenberg-Marquardt reaches 0.5 chi2 = 2339.2 on this file from a good start (its
  // loader's reading of LANDMARK: bearing-range, --isam-landmarks gtsam). The batch gets there
  // from its default start (the EKF's estimate) and after the SEIF (--smooth); from odometry
  // alone it stalls in a wrong minimum, as GTSAM's does (170 941), and says so.
  const std::string isam = kData + "/victoria-park-isam/victoria_park.txt";
  if (!fs::exists(isam)) GTEST_SKIP() << "victoria_park.txt not found at " << isam;
  const auto dir = scratchDir("isam-batch");
  const std::string common = "run --dataset " + isam + " --isam-landmarks gtsam ";
  for (const std::string& how : {std::string("--filter batch"), std::string("--filter seif --smooth")}) {
    const fs::path out = dir / (how.find("smooth") != std::string::npos ? "smooth" : "batch");
    const auto r = runCli(common + how + " --out " + out.string());
    ASSERT_EQ(r.status, 0) << r.err;
    const auto m = nlohmann::json::parse(slurp(out / "metrics.json"));
    const auto& b = m["batch"];
    EXPECT_NEAR(b["final_cost"].get<double>(), 2339.2, 0.001 * 2339.2) << how;
    EXPECT_TRUE(b["converged"].get<bool>()) << how;
    EXPECT_EQ(b["costs"].front().get<double>(), b["initial_cost"].get<double>());
    EXPECT_EQ(b["costs"].back().get<double>(), b["final_cost"].get<double>());
    EXPECT_LT(b["gradient_norm"].get<double>(), 1e-9 * b["initial_gradient_norm"].get<double>()) << how;
    EXPECT_EQ(b["landmarks"], 151);
    EXPECT_LT(b["poses"].get<int>(), 6969);  // only where observations are made, and the ends
    EXPECT_EQ(lines(out / "trajectory.tum"), 6969u) << how;
    EXPECT_EQ(lines(out / "map.csv"), 152u) << how;
  }
  const auto s = nlohmann::json::parse(slurp(dir / "smooth" / "metrics.json"));
  EXPECT_EQ(s["batch"]["init"], "seif");
  EXPECT_TRUE(s["smooth"].get<bool>());
  EXPECT_GT(s["filter_before_smoothing"]["map_distance_to_batch"].get<double>(), 0.0);
  EXPECT_EQ(lines(dir / "smooth" / "trajectory_filter.tum"), 6969u);
  EXPECT_EQ(lines(dir / "smooth" / "map_filter.csv"), 152u);
  EXPECT_NE(slurp(dir / "smooth" / "map_filter.csv"), slurp(dir / "smooth" / "map.csv"));

  const auto o = runCli(common + "--filter batch:init=odometry --out " + (dir / "odometry").string());
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_NE(o.out.find("WARNING: the batch stopped at its iteration limit"), std::string::npos) << o.out;
  const auto m = nlohmann::json::parse(slurp(dir / "odometry" / "metrics.json"));
  EXPECT_FALSE(m["batch"]["converged"].get<bool>());
  EXPECT_GT(m["batch"]["final_cost"].get<double>(), 100000.0);
  EXPECT_EQ(runCli("run --dataset " + isam + " --filter batch --smooth --out " + dir.string()).status, 1);
  fs::remove_all(dir);
}

TEST(CliDatasets, BatchOnVictoriaParkWithItsCovariances) {
  // 68 789 steps, poses only at the 7 000-odd laser scans with trees: the MAP with the map's
  // and every pose's marginal covariance (README, Victoria Park: the time and the GPS error).
  const std::string vp = kData + "/victoria-park";
  if (!fs::exists(vp + "/controls.txt")) GTEST_SKIP() << "Victoria Park not found at " << vp;
  const auto dir = scratchDir("vp-batch");
  const auto r = runCli("run --dataset " + vp + " --filter batch --trajectory-covariance on --out " + dir.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto m = nlohmann::json::parse(slurp(dir / "metrics.json"));
  EXPECT_TRUE(m["batch"]["converged"].get<bool>());
  EXPECT_LT(m["batch"]["poses"].get<int>(), 8000);
  EXPECT_GT(m["batch"]["constraints"].get<int>(), 0);
  EXPECT_LT(m["batch"]["gradient_norm"].get<double>(), 1e-9 * m["batch"]["initial_gradient_norm"].get<double>());
  EXPECT_EQ(m["landmarks"], 299);
  EXPECT_LE(m["gps_rmse"].get<double>(), 3.0);
  EXPECT_EQ(lines(dir / "trajectory_cov.csv"), 68791u);  // header + the start + 68 789 steps
  EXPECT_EQ(lines(dir / "map.csv"), 300u);
  fs::remove_all(dir);
}

TEST(CliDatasets, BatchOnMrclamBeatsTheFilters) {
  const std::string mr = kData + "/mrclam/MRCLAM_Dataset6";
  if (!fs::exists(mr + "/Robot1_Odometry.dat")) GTEST_SKIP() << "MRCLAM not found at " << mr;
  const auto dir = scratchDir("mrclam-batch");
  double ate[2];
  int i = 0;
  for (const char* f : {"batch", "ekf"}) {
    const auto r = runCli("run --dataset " + mr + " --robot 1 --filter " + f + " --out " + (dir / f).string());
    ASSERT_EQ(r.status, 0) << r.err;
    ate[i++] = nlohmann::json::parse(slurp(dir / f / "metrics.json"))["ate_rmse"].get<double>();
  }
  std::printf("MRCLAM robot 1, aligned ATE: batch %.3f m, EKF %.3f m\n", ate[0], ate[1]);
  EXPECT_LT(ate[0], ate[1]);
  fs::remove_all(dir);
}

// Bad data in any format: one line naming file and line, exit status 2.
TEST(CliDatasets, MalformedFilesExitTwoNamingFileAndLine) {
  const auto dir = scratchDir("bad");
  const struct {
    const char* name;
    const char* text;
    const char* where;
  } cases[] = {
      {"truncated.txt", "ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01\nODOMETRY 1 2 1 0\n", "truncated.txt:2:"},
      {"nan.txt", "ODOMETRY 0 1 nan 0 0 0.01 0 0 0.01 0 0.01\n", "nan.txt:1:"},
      {"letters.g2o", "EDGE_SE2 0 1 one 0 0 1 0 0 1 0 1\n", "letters.g2o:1:"},
      {"tag.txt", "ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01\nPOINT 1 2\n", "tag.txt:2: unknown record tag"},
      {"both.txt", "ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01\nLANDMARK 1 0 1 1 0.4 0 0.4\n", "both.txt:2:"},
      {"back.txt", "ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01\nODOMETRY 0 2 1 0 0 0.01 0 0 0.01 0 0.01\n", "back.txt:2:"},
  };
  for (const auto& c : cases) {
    std::ofstream(dir / c.name) << c.text;
    const auto r = runCli("run --dataset " + (dir / c.name).string() + " --out " + (dir / "out").string());
    EXPECT_EQ(r.status, 2) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.where), std::string::npos) << r.err;
  }
  fs::create_directories(dir / "vp");
  std::ofstream(dir / "vp" / "controls.txt") << "1 2 0.1\n0.5 2 0.1\n";
  std::ofstream(dir / "vp" / "tree_observations_associated_UTS.txt") << "";
  auto r = runCli("run --dataset " + (dir / "vp").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("controls.txt:2: time 0.5 goes backwards"), std::string::npos) << r.err;
  std::ofstream(dir / "unknown.csv") << "a,b,c\n";
  r = runCli("run --dataset " + (dir / "unknown.csv").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("cannot tell the dataset's format"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("victoria-park"), std::string::npos) << r.err;
  r = runCli("run --dataset " + (dir / "unknown.csv").string() + " --sigma-speed 0.1 --format isam --out " +
             (dir / "out").string());
  EXPECT_EQ(r.status, 1) << r.err;  // a noise value the format does not take is a usage error
  fs::remove_all(dir);
}

}  // namespace
