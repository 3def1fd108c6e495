// `seif plot RUN_DIR`: draws a `seif run` output folder into RUN_DIR/map.png; `seif run`
// keeps the dataset's GPS fixes in gps.csv for it.
#include "cli_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;

bool hasMatplotlib() { return std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0; }

/// A PNG of more than a few kilobytes: something was drawn.
void expectDrawing(const fs::path& png) {
  ASSERT_TRUE(fs::exists(png)) << png;
  const std::string bytes = slurp(png);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  EXPECT_GT(bytes.size(), 20000u);
}

/// The lines of `from` whose first number is at most `t_max` (comments kept).
void copyUntil(const fs::path& from, const fs::path& to, double t_max) {
  std::ifstream in(from);
  std::ofstream out(to);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    double t = 0.0;
    if (line.empty() || line[0] == '#' || !(s >> t) || t <= t_max) out << line << '\n';
  }
}

TEST(PlotCli, DrawsARunFolderIntoMapPng) {
  if (!hasMatplotlib()) GTEST_SKIP() << "/usr/bin/python3 with matplotlib is needed";
  const auto dir = scratchDir("plot");
  ASSERT_EQ(runCli("simulate --preset paper --landmarks 20 --steps 150 --seed 2 --out " + (dir / "W").string()).status, 0);
  ASSERT_EQ(runCli("run --dataset " + (dir / "W").string() + " --filter ekf --out " + (dir / "R").string()).status, 0);
  EXPECT_FALSE(fs::exists(dir / "R" / "gps.csv"));  // the simulator has no GPS
  // but ground truth: a pose per step after the start, and its 20 landmarks
  const std::string truth = slurp(dir / "R" / "groundtruth.tum");
  EXPECT_GE(std::count(truth.begin(), truth.end(), '\n'), 150);
  const std::string landmarks = slurp(dir / "R" / "landmarks_groundtruth.csv");
  EXPECT_EQ(landmarks.rfind("id,x,y\n", 0), 0u);
  EXPECT_EQ(std::count(landmarks.begin(), landmarks.end(), '\n'), 21);
  const auto r = runCli("plot " + (dir / "R").string());
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  expectDrawing(dir / "R" / "map.png");
  EXPECT_EQ(runCli("plot " + dir.string()).status, 2);  // not a run folder
  fs::remove_all(dir);
}

TEST(PlotCli, DrawsTheGpsFixesARunKept) {
  const fs::path vp = fs::path(SEIF_SHARED_DATA_DIR) / "victoria-park";
  if (!fs::exists(vp / "gps.txt")) GTEST_SKIP() << "Victoria Park not found at " << vp;
  const auto dir = scratchDir("plot-gps");
  fs::create_directories(dir / "VP");
  for (const char* f : {"controls.txt", "tree_observations_associated_UTS.txt", "gps.txt", "tree_detections.txt"}) {
    copyUntil(vp / f, dir / "VP" / f, 120.0);  // the first two minutes
  }
  fs::copy_file(vp / "laser_scan_times.txt", dir / "VP" / "laser_scan_times.txt");
  const auto run = runCli("run --dataset " + (dir / "VP").string() + " --filter seif --out " + (dir / "R").string());
  ASSERT_EQ(run.status, 0) << run.out << run.err;
  const std::string gps = slurp(dir / "R" / "gps.csv");
  EXPECT_EQ(gps.rfind("time,x,y\n", 0), 0u);
  EXPECT_GT(std::count(gps.begin(), gps.end(), '\n'), 10);
  if (!hasMatplotlib()) GTEST_SKIP() << "/usr/bin/python3 with matplotlib is needed";
  const auto r = runCli("plot " + (dir / "R").string() + " --title 'Victoria Park, 2 min'");
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  expectDrawing(dir / "R" / "map.png");
  fs::remove_all(dir);
}

}  // namespace
