// `seif run` and `seif convert` end to end on every dataset format: what a user runs, what
// they get back (outputs, figures in metrics.json, exit status 2 with file:line on bad data).
#include "cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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
  }
  ASSERT_EQ(runCli("convert " + isam + " --to g2o --out " + (dir / "vp.g2o").string()).status, 0);
  ASSERT_EQ(runCli("convert " + (dir / "vp.g2o").string() + " --to isam --out " + (dir / "vp.txt").string()).status, 0);
  const auto r = runCli("run --dataset " + (dir / "vp.g2o").string() + " --filter seif --out " + (dir / "g2o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(dir / "g2o" / "trajectory.tum"), slurp(dir / "seif" / "trajectory.tum"));
  EXPECT_EQ(slurp(dir / "g2o" / "map.csv"), slurp(dir / "seif" / "map.csv"));
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
