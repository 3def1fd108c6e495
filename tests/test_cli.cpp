// The command-line tool end to end, as a user runs it.
#include "cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <vector>

namespace {

using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;

const std::string kMrclam = std::string(SEIF_SHARED_DATA_DIR) + "/mrclam/MRCLAM_Dataset6";

std::vector<std::vector<double>> readRows(const std::filesystem::path& file, char sep) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(slurp(file));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || std::isalpha(static_cast<unsigned char>(line[0]))) continue;
    for (char& c : line) if (c == sep) c = ' ';
    std::istringstream ls(line);
    std::vector<double> row;
    double v;
    while (ls >> v) row.push_back(v);
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json readJson(const std::filesystem::path& file) { return nlohmann::json::parse(slurp(file)); }

}  // namespace

TEST(Cli, HelpTeachesAndBadUsageExitsWithOne) {
  const auto help = runCli("--help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("simulate"), std::string::npos);
  EXPECT_NE(help.out.find("run"), std::string::npos);
  const auto run_help = runCli("run --help");
  EXPECT_EQ(run_help.status, 0);
  EXPECT_NE(run_help.out.find("--active"), std::string::npos);
  EXPECT_EQ(runCli("run --filter kalman --dataset /").status, 1);
  EXPECT_EQ(runCli("frobnicate").status, 1);
}

TEST(Cli, EkfAndEifAgreeOnASimulatedWorld) {
  const auto dir = scratchDir("ekf-eif");
  const auto sim = runCli("simulate --preset uniform --landmarks 50 --seed 7 --out " + (dir / "W").string());
  ASSERT_EQ(sim.status, 0) << sim.err;
  for (const std::string f : {"ekf", "eif"}) {
    const auto r = runCli("run --dataset " + (dir / "W").string() + " --filter " + f + " --out " + (dir / f).string());
    ASSERT_EQ(r.status, 0) << r.err;
  }
  const auto te = readRows(dir / "ekf" / "trajectory.tum", ' ');
  const auto ti = readRows(dir / "eif" / "trajectory.tum", ' ');
  ASSERT_EQ(te.size(), ti.size());
  ASSERT_GT(te.size(), 400u);
  double worst = 0;
  for (std::size_t i = 0; i < te.size(); ++i) {
    worst = std::max(worst, std::hypot(te[i][1] - ti[i][1], te[i][2] - ti[i][2]));
  }
  EXPECT_LT(worst, 1e-6);
  const auto me = readRows(dir / "ekf" / "map.csv", ',');
  const auto mi = readRows(dir / "eif" / "map.csv", ',');
  ASSERT_EQ(me.size(), mi.size());
  ASSERT_GT(me.size(), 30u);
  for (std::size_t i = 0; i < me.size(); ++i) {
    EXPECT_EQ(me[i][0], mi[i][0]);
    EXPECT_LT(std::hypot(me[i][1] - mi[i][1], me[i][2] - mi[i][2]), 1e-6);
  }
  const auto m = readJson(dir / "ekf" / "metrics.json");
  for (const char* key : {"steps", "landmarks", "seconds", "us_per_step", "links", "landmark_rmse",
                          "ate_rmse", "dead_reckoning_ate_rmse"}) {
    EXPECT_TRUE(m.contains(key)) << key;
  }
  EXPECT_LT(m["ate_rmse"].get<double>(), m["dead_reckoning_ate_rmse"].get<double>());
  std::filesystem::remove_all(dir);
}

TEST(Cli, SeifRunsOnASimulatedWorldAndReportsItsStructure) {
  const auto dir = scratchDir("seif-run");
  ASSERT_EQ(runCli("simulate --preset paper --seed 3 --out " + (dir / "W").string()).status, 0);
  const auto r = runCli("run --dataset " + (dir / "W").string() +
                        " --filter seif --active 4 --relax 5 --out " + (dir / "R").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto m = readJson(dir / "R" / "metrics.json");
  EXPECT_LE(m["max_robot_links"].get<int>(), 4);
  EXPECT_EQ(m["seif"]["active"].get<int>(), 4);
  EXPECT_LT(m["landmark_rmse"].get<double>(), 0.1);
  std::filesystem::remove_all(dir);
}

TEST(Cli, CorruptedDatasetsGiveOneLineAndStatusTwo) {
  const auto dir = scratchDir("corrupt");
  ASSERT_EQ(runCli("simulate --preset paper --steps 50 --seed 2 --out " + (dir / "W").string()).status, 0);
  struct Damage {
    std::string file;
    std::string what;
    std::string (*apply)(const std::string& line);
  };
  const std::vector<Damage> damages = {
      {"Robot1_Odometry.dat", "truncated", [](const std::string& l) { return l.substr(0, l.find('\t')); }},
      {"Robot1_Measurement.dat", "nan", [](const std::string& l) { return l.substr(0, l.rfind('\t')) + "\tnan"; }},
      {"Robot1_Odometry.dat", "letter", [](const std::string& l) { return l.substr(0, l.rfind('\t')) + "\t0.1x3"; }},
      {"Robot1_Groundtruth.dat", "time back", [](const std::string&) { return std::string("0\t0\t0\t0"); }},
  };
  for (const Damage& d : damages) {
    const auto copy = dir / ("C-" + std::to_string(&d - damages.data()));
    std::filesystem::copy(dir / "W", copy);
    // Damage the 10th data line (line numbers count the 4 comment lines).
    std::istringstream in(slurp(copy / d.file));
    std::string line, text;
    int n = 0, damaged_line = 0;
    while (std::getline(in, line)) {
      ++n;
      if (line[0] != '#' && damaged_line == 0 && n >= 14) {
        line = d.apply(line);
        damaged_line = n;
      }
      text += line + "\n";
    }
    std::ofstream(copy / d.file) << text;
    const auto r = runCli("run --dataset " + copy.string() + " --filter ekf --out " + (copy / "R").string());
    EXPECT_EQ(r.status, 2) << d.what << ": " << r.err;
    const std::string expected = (copy / d.file).string() + ":" + std::to_string(damaged_line) + ":";
    EXPECT_EQ(r.err.rfind(expected, 0), 0u) << d.what << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << d.what << ": " << r.err;
  }
  // A missing file.
  const auto missing = dir / "missing";
  std::filesystem::copy(dir / "W", missing);
  std::filesystem::remove(missing / "Robot1_Measurement.dat");
  const auto r = runCli("run --dataset " + missing.string() + " --out " + (missing / "R").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("Robot1_Measurement.dat"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

TEST(CliMrclam, SlamBeatsDeadReckoningOnAllFiveRobots) {
  if (!std::filesystem::exists(kMrclam)) GTEST_SKIP() << "MRCLAM dataset 6 not found at " << kMrclam;
  const auto dir = scratchDir("mrclam");
  for (int robot = 1; robot <= 5; ++robot) {
    for (const std::string f : {"ekf", "seif"}) {
      const auto out = dir / (f + std::to_string(robot));
      const auto r = runCli("run --dataset " + kMrclam + " --robot " + std::to_string(robot) +
                            " --filter " + f + " --out " + out.string());
      ASSERT_EQ(r.status, 0) << r.err;
      const auto m = readJson(out / "metrics.json");
      EXPECT_EQ(m["landmarks"].get<int>(), 15) << f << " robot " << robot;
      EXPECT_LT(m["ate_rmse"].get<double>(), 0.5 * m["dead_reckoning_ate_rmse"].get<double>())
          << f << " robot " << robot;
      EXPECT_LT(m["landmark_rmse"].get<double>(), 0.5) << f << " robot " << robot;
    }
  }
  std::filesystem::remove_all(dir);
}
