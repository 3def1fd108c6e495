// seif run --checkpoint-every N --checkpoint FILE / --resume FILE: a run resumed from a
// checkpoint at several points ends with the outputs of the run never interrupted, for
// every filter that can be saved; damaged or foreign checkpoints exit 2 with one line.
#include "cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::estimateMetrics;
using seif::test::slurp;

namespace {


class CliCheckpoint : public ::testing::TestWithParam<std::string> {};

TEST_P(CliCheckpoint, AResumedRunEndsAsTheUninterruptedOne) {
  const auto dir = scratchDir("checkpoint");
  ASSERT_EQ(runCli("simulate --preset paper --seed 5 --out " + (dir / "data").string()).status, 0);
  const std::string run = "run --dataset " + (dir / "data").string() + " --filter '" + GetParam() + "'";
  ASSERT_EQ(runCli(run + " --out " + (dir / "full").string()).status, 0);
  for (int every : {37, 250, 499}) {  // the paper world has 500 steps
    const std::string n = std::to_string(every);
    const fs::path ckpt = dir / (n + ".ckpt");
    const auto saved = runCli(run + " --checkpoint-every " + std::to_string(every) + " --checkpoint " + ckpt.string() +
                              " --out " + (dir / "saving").string());
    ASSERT_EQ(saved.status, 0) << saved.err;
    const fs::path resumed = dir / (n + "-resumed");
    const auto r = runCli("run --dataset " + (dir / "data").string() + " --resume " + ckpt.string() + " --out " +
                          resumed.string());
    ASSERT_EQ(r.status, 0) << r.err;
    for (const char* file : {"trajectory.tum", "dead_reckoning.tum", "map.csv"}) {
      EXPECT_EQ(slurp(resumed / file), slurp(dir / "full" / file)) << GetParam() << ", every " << every << ": " << file;
    }
    const nlohmann::json a = estimateMetrics(resumed), b = estimateMetrics(dir / "full");
    for (const auto& [key, value] : b.items()) {
      EXPECT_EQ(a.value(key, nlohmann::json()), value) << GetParam() << ", every " << every << ": " << key;
    }
    EXPECT_EQ(a.size(), b.size());
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Filters, CliCheckpoint,
                         ::testing::Values("ekf", "eif", "seif", "seif:sparsify=eseif,beta=4",
                                           "seif:relax-order=random,linearization=fej"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           for (char& c : n) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return n;
                         });

TEST(CliCheckpoint, DamagedForeignAndMismatchedCheckpointsExit2WithOneLine) {
  const auto dir = scratchDir("checkpoint-bad");
  ASSERT_EQ(runCli("simulate --preset paper --seed 5 --out " + (dir / "data").string()).status, 0);
  ASSERT_EQ(runCli("simulate --preset paper --seed 6 --out " + (dir / "other").string()).status, 0);
  const fs::path ckpt = dir / "c.ckpt";
  ASSERT_EQ(runCli("run --dataset " + (dir / "data").string() + " --checkpoint-every 100 --checkpoint " +
                   ckpt.string() + " --out " + (dir / "r").string())
                .status,
            0);
  const std::string bytes = slurp(ckpt);
  std::ofstream(dir / "truncated.ckpt", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::ofstream(dir / "foreign.ckpt") << "# not a checkpoint\n";
  for (const fs::path& bad : {dir / "truncated.ckpt", dir / "foreign.ckpt", dir / "missing.ckpt"}) {
    const auto r = runCli("run --dataset " + (dir / "data").string() + " --resume " + bad.string() + " --out " +
                          (dir / "x").string());
    EXPECT_EQ(r.status, 2) << bad;
    EXPECT_NE(r.err.find(bad.filename().string()), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const auto other = runCli("run --dataset " + (dir / "other").string() + " --resume " + ckpt.string() + " --out " +
                            (dir / "x").string());
  EXPECT_EQ(other.status, 2);
  EXPECT_NE(other.err.find("not of"), std::string::npos) << other.err;
  EXPECT_EQ(runCli("run --dataset " + (dir / "data").string() + " --checkpoint-every 10 --out " + (dir / "x").string())
                .status,
            1);
  fs::remove_all(dir);
}

}  // namespace
