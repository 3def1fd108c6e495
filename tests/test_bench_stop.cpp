// A stopped `seif bench` keeps the cases it finished (BenchRequest::stop; the CLI's Ctrl-C).
#include "cli_support.hpp"

#include <seif/eval/bench.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>

namespace {

seif::BenchRequest smallBench() {
  seif::BenchRequest request;
  request.filters = {"ekf", "seif"};
  request.landmarks = {100, 150};
  request.window = 10;
  request.repeat = 1;
  return request;
}

// Stopped after its first case (row_done sets the flag), the study runs no other and says so.
TEST(BenchStop, AStoppedStudyKeepsTheCasesItFinished) {
  seif::BenchRequest request = smallBench();
  std::atomic<bool> stop{false};
  request.stop = &stop;
  const seif::BenchReport report = seif::runBench(request, [&](const seif::BenchRow&) { stop = true; });
  EXPECT_TRUE(report.interrupted);
  ASSERT_EQ(report.rows.size(), 1u);
  EXPECT_EQ(report.rows[0].filter, "ekf");
  EXPECT_EQ(report.rows[0].landmarks, 100);
  EXPECT_TRUE(report.rows[0].measurement.has_value()) << report.rows[0].skipped;
  EXPECT_TRUE(nlohmann::json::parse(seif::benchJson(report))["interrupted"].get<bool>());
  EXPECT_EQ(seif::interruptedText(report), "bench interrupted after 1 case");
  // Not stopped: every case, and not interrupted.
  seif::BenchRequest whole = smallBench();
  whole.filters = {"ekf"};
  const seif::BenchReport all = seif::runBench(whole);
  EXPECT_FALSE(all.interrupted);
  EXPECT_EQ(all.rows.size(), 2u);
  EXPECT_FALSE(nlohmann::json::parse(seif::benchJson(all))["interrupted"].get<bool>());
}

// Ctrl-C (SIGINT to the process group, as a terminal sends it): the cases finished are in
// bench.json, and the exit status is 130. The EKF's cases grow as N^2 per step: the signal
// comes while the small ones are done and a large one runs.
TEST(BenchStop, CtrlCWritesTheCasesFinished) {
  const auto dir = seif::test::scratchDir("bench-interrupted");
  const auto r = seif::test::runCliSignalled("bench --filters ekf --landmarks 100,150,200,3000,4000,5000 --window 10 "
                                             "--repeat 1 --max-seconds 100000 --no-figure --out " + dir.string(),
                                             "INT", 5.0);
  EXPECT_EQ(r.status, 130) << r.err;
  EXPECT_NE(r.err.find("bench interrupted after "), std::string::npos) << r.err;
  const nlohmann::json j = nlohmann::json::parse(seif::test::slurp(dir / "bench.json"));
  EXPECT_TRUE(j["interrupted"].get<bool>());
  ASSERT_GE(j["results"].size(), 1u) << r.out;
  EXPECT_LT(j["results"].size(), 6u) << r.out;
  for (const auto& row : j["results"]) EXPECT_FALSE(row["us_per_step_median"].is_null()) << row;
}

}  // namespace
