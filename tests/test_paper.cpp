// Tests of the paper's experiment: the statistics (eval/stats.hpp) against values computed
// by hand and published t tables, one run of the experiment (eval/paper.hpp), and
// `seif paper` end to end through the executable.
#include <seif/core/errors.hpp>
#include <seif/eval/paper.hpp>
#include <seif/eval/stats.hpp>

#include "cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdint>

#include <cmath>
#include <filesystem>
#include <random>
#include <utility>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;

// ---------------------------------------------------------------- statistics ----------

TEST(Stats, KnownSample) {
  // {2,4,4,4,5,5,7,9}: mean 5, squared deviations sum to 32, s = sqrt(32/7) = 2.13809;
  // t(0.975, 7) = 2.364624; half-width = 2.364624 * 2.13809 / sqrt(8) = 1.787488.
  const std::vector<double> xs = {2, 4, 4, 4, 5, 5, 7, 9};
  EXPECT_DOUBLE_EQ(seif::sampleMean(xs), 5.0);
  EXPECT_NEAR(seif::sampleStdDev(xs), std::sqrt(32.0 / 7.0), 1e-12);
  EXPECT_NEAR(seif::sampleStdDev(xs), 2.138090, 1e-6);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 7), 2.364624, 1e-6);
  EXPECT_NEAR(seif::ci95HalfWidth(xs), 1.787488, 1e-5);
  EXPECT_DOUBLE_EQ(seif::median(xs), 4.5);
  const seif::Summary s = seif::summarize(xs);
  EXPECT_EQ(s.n, 8u);
  EXPECT_DOUBLE_EQ(s.min, 2.0);
  EXPECT_DOUBLE_EQ(s.max, 9.0);
  EXPECT_NEAR(s.ci95, 1.787488, 1e-5);
}

TEST(Stats, DegenerateSamples) {
  EXPECT_TRUE(std::isnan(seif::sampleMean(std::vector<double>{})));
  EXPECT_TRUE(std::isnan(seif::median({})));
  EXPECT_EQ(seif::sampleStdDev(std::vector<double>{3.0}), 0.0);
  EXPECT_EQ(seif::ci95HalfWidth(std::vector<double>{3.0}), 0.0);
  EXPECT_EQ(seif::ci95HalfWidth(std::vector<double>{3.0, 3.0, 3.0}), 0.0);
  EXPECT_DOUBLE_EQ(seif::median({3.0, 1.0, 2.0}), 2.0);
}

TEST(Stats, StudentTQuantilesMatchTables) {
  // Two-sided 95 % critical values from standard t tables.
  EXPECT_NEAR(seif::studentTQuantile(0.975, 1), 12.706205, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 2), 4.302653, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 3), 3.182446, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 5), 2.570582, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 10), 2.228139, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 30), 2.042272, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 199), 1.971957, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 1000), 1.962339, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.975, 1e7), 1.959964, 1e-5);  // -> normal
  // Other levels, and symmetry.
  EXPECT_NEAR(seif::studentTQuantile(0.95, 5), 2.015048, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.995, 20), 2.845340, 1e-5);
  EXPECT_NEAR(seif::studentTQuantile(0.025, 7), -2.364624, 1e-5);
  EXPECT_EQ(seif::studentTQuantile(0.5, 4), 0.0);
  EXPECT_THROW(seif::studentTQuantile(1.0, 4), seif::InvalidArgument);
  EXPECT_THROW(seif::studentTQuantile(0.9, 0), seif::InvalidArgument);
}

TEST(Stats, QuantileInvertsCdf) {
  for (double dof : {1.0, 2.0, 3.0, 4.5, 7.0, 30.0, 250.0}) {
    for (double p : {0.01, 0.2, 0.6, 0.9, 0.975, 0.999}) {
      EXPECT_NEAR(seif::studentTCdf(seif::studentTQuantile(p, dof), dof), p, 1e-11)
          << "dof " << dof << " p " << p;
    }
  }
  EXPECT_NEAR(seif::incompleteBeta(1.0, 1.0, 0.3), 0.3, 1e-14);
  EXPECT_NEAR(seif::incompleteBeta(2.5, 2.5, 0.5), 0.5, 1e-14);
  EXPECT_NEAR(seif::incompleteBeta(2.0, 3.0, 0.4), 0.5248, 1e-12);  // 1 - sum_{k<2} C(4,k)...
}

TEST(Stats, CoverageOfNormalSamples) {
  // The 95 % interval of n = 5 normal samples covers the true mean ~95 % of the time; with
  // 1.96 instead of t(0.975, 4) = 2.776 it would cover only ~88 %.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(3.0, 2.0);
  int covered = 0;
  const int trials = 20000;
  for (int k = 0; k < trials; ++k) {
    std::vector<double> xs(5);
    for (double& x : xs) x = normal(rng);
    covered += std::fabs(seif::sampleMean(xs) - 3.0) <= seif::ci95HalfWidth(xs);
  }
  const double rate = static_cast<double>(covered) / trials;
  EXPECT_NEAR(rate, 0.95, 0.006);  // 99.9 % bound: 3.29 * sqrt(.95 * .05 / 20000) = 0.005
}

TEST(Stats, PairedRatioByHand) {
  // x = (3, 5, 4), y = (1, 2, 3): R = 4 / 2 = 2, residuals x - 2 y = (1, 1, -2), sd sqrt(3),
  // half-width t(0.975, 2) sqrt(3) / (sqrt(3) * 2) = 4.302653 / 2.
  const std::vector<double> x{3.0, 5.0, 4.0}, y{1.0, 2.0, 3.0};
  const seif::PairedRatio r = seif::pairedRatio(x, y);
  EXPECT_DOUBLE_EQ(r.ratio, 2.0);
  EXPECT_NEAR(r.ci95, 4.302653 / 2.0, 1e-6);
  EXPECT_EQ(r.pairs, 3u);
  // A pair with a NaN (a run a filter stopped in) is left out of both means.
  const std::vector<double> xn{3.0, 5.0, 4.0, std::nan("")}, yn{1.0, 2.0, 3.0, 100.0};
  EXPECT_DOUBLE_EQ(seif::pairedRatio(xn, yn).ratio, 2.0);
  EXPECT_EQ(seif::pairedRatio(xn, yn).pairs, 3u);
  EXPECT_TRUE(std::isnan(seif::pairedRatio(std::vector<double>{}, std::vector<double>{}).ratio));
  EXPECT_EQ(seif::pairedRatio(std::vector<double>{1.0}, std::vector<double>{2.0}).ci95, 0.0);
  EXPECT_THROW(seif::pairedRatio(x, std::vector<double>{1.0}), seif::InvalidArgument);
}

TEST(Stats, PairedRatioCoversTheRatioOfTheExpectations) {
  // Paired errors of two filters on the same runs: y_i ~ Exp-like spread around 1, x_i =
  // 1.3 y_i + noise. E[x] / E[y] = 1.3; the delta-method interval over 50 pairs covers it
  // about 95 % of the time (a few points less: the delta method is asymptotic).
  std::mt19937_64 rng(11);
  std::gamma_distribution<double> spread(4.0, 0.25);  // mean 1
  std::normal_distribution<double> noise(0.0, 0.2);
  int covered = 0;
  const int trials = 4000;
  for (int k = 0; k < trials; ++k) {
    std::vector<double> x(50), y(50);
    for (std::size_t i = 0; i < 50; ++i) {
      y[i] = spread(rng);
      x[i] = 1.3 * y[i] + noise(rng);
    }
    const seif::PairedRatio r = seif::pairedRatio(x, y);
    covered += std::fabs(r.ratio - 1.3) <= r.ci95;
  }
  const double rate = static_cast<double>(covered) / trials;
  EXPECT_GT(rate, 0.93);
  EXPECT_LT(rate, 0.97);
}

// ---------------------------------------------------------------- one run -------------

TEST(PaperExperiment, OneRunIsDeterministicAndConsistent) {
  seif::PaperOptions options;
  options.steps = 150;  // shorter than the paper's 500: a test, not the experiment
  options.sweep_active = {4};
  seif::PaperRunDetail detail;
  const seif::PaperRun a = seif::runPaperExperiment(3, options, &detail);
  const seif::PaperRun b = seif::runPaperExperiment(3, options);
  ASSERT_EQ(a.filters.size(), 4u);
  EXPECT_EQ(a.filters[0].name, "ekf");
  EXPECT_EQ(a.filters[1].name, "seif_exact");
  EXPECT_EQ(a.filters[2].name, "seif");
  EXPECT_EQ(a.filters[3].name, "seif_active_4");
  for (std::size_t f = 0; f < a.filters.size(); ++f) {
    EXPECT_EQ(a.filters[f].mse, b.filters[f].mse);
    EXPECT_EQ(a.filters[f].stats.links, b.filters[f].stats.links);
    EXPECT_EQ(a.filters[f].step_seconds.size(), a.steps);
    EXPECT_GT(a.filters[f].mapped, 0u);
    EXPECT_EQ(a.filters[f].mapped, a.filters[0].mapped);  // identical data, known association
    EXPECT_NEAR(a.filters[f].rmse * a.filters[f].rmse, a.filters[f].mse, 1e-15);
    // The final error is landmarkMse() of the filter after the last step.
    EXPECT_DOUBLE_EQ(seif::landmarkMse(*detail.filters[f], detail.data.landmarks), a.filters[f].mse);
  }
  const std::size_t n = a.filters[0].mapped;
  EXPECT_EQ(a.filters[0].stats.links, n * (n + 1) / 2);  // the EKF's information is dense
  EXPECT_LE(a.filters[2].stats.robot_links, 6u);
  EXPECT_LE(a.filters[3].stats.robot_links, 4u);
  EXPECT_LT(a.filters[2].stats.links, a.filters[0].stats.links);
  const seif::PaperRun other = seif::runPaperExperiment(4, options);
  EXPECT_NE(other.filters[0].mse, a.filters[0].mse);
}

TEST(PaperStudy, RunPaperIsItsRunsWhateverTheThreadsAndWritesItsFiles) {
  seif::PaperRequest request;
  request.runs = 3;
  request.seed = 11;
  request.options.steps = 120;
  request.jobs = 1;
  const seif::PaperReport one = seif::runPaper(request);
  request.jobs = 2;
  const seif::PaperReport two = seif::runPaper(request);
  ASSERT_EQ(one.runs.size(), 3u);
  ASSERT_EQ(two.runs.size(), 3u);
  EXPECT_EQ(two.jobs, 2u);
  for (std::size_t r = 0; r < one.runs.size(); ++r) {
    const seif::PaperRun alone = seif::runPaperExperiment(request.seed + r, request.options);
    EXPECT_EQ(one.runs[r].seed, request.seed + r);
    for (std::size_t f = 0; f < alone.filters.size(); ++f) {
      EXPECT_EQ(one.runs[r].filters[f].mse, alone.filters[f].mse);
      EXPECT_EQ(two.runs[r].filters[f].mse, alone.filters[f].mse);
      EXPECT_EQ(two.runs[r].filters[f].stats.links, alone.filters[f].stats.links);
    }
  }
  for (std::size_t f = 0; f < one.summaries.size(); ++f) {
    EXPECT_EQ(one.summaries[f].error.mean, two.summaries[f].error.mean);
    EXPECT_EQ(one.summaries[f].ratio, two.summaries[f].ratio);
  }
  EXPECT_EQ(one.typical, two.typical);
  EXPECT_EQ(one.typical_detail.filters.size(), 3u);
  EXPECT_NE(seif::paperSummaryText(one).find("SEIF (constant time)"), std::string::npos);

  const auto dir = scratchDir("paper-study");
  seif::writePaperResults(one, dir);
  for (const char* file : {"results.json", "table.md", "figure_data/ekf.json", "figure_data/seif.json",
                           "figure_data/seif_exact.json"}) {
    EXPECT_GT(std::filesystem::file_size(dir / file), 100u) << file;
  }

  request.runs = 0;
  EXPECT_THROW(seif::runPaper(request), seif::InvalidArgument);
  request.runs = 2;
  request.seed = UINT64_MAX;
  EXPECT_THROW(seif::checkPaperRequest(request), seif::InvalidArgument);
}

// Stopped once two runs are done (one thread: in order), the study runs no other and
// summarises the two as a study of those alone would, and says so; stopped before any run,
// it throws Interrupted.
TEST(PaperStudy, AStoppedStudyKeepsTheRunsThatRan) {
  seif::PaperRequest request;
  request.runs = 20;
  request.seed = 11;
  request.options.steps = 60;
  request.jobs = 1;
  std::atomic<bool> stop{false};
  request.stop = &stop;
  const seif::PaperReport stopped = seif::runPaper(request, [&](std::size_t done, std::size_t) {
    if (done == 2) stop = true;
  });
  EXPECT_TRUE(stopped.interrupted);
  EXPECT_EQ(stopped.request.stop, nullptr);
  ASSERT_EQ(stopped.runs.size(), 2u);
  EXPECT_TRUE(stopped.failed.empty());
  request.runs = 2;
  request.stop = nullptr;
  const seif::PaperReport two = seif::runPaper(request);
  EXPECT_FALSE(two.interrupted);
  for (std::size_t f = 0; f < two.summaries.size(); ++f) {
    EXPECT_EQ(stopped.summaries[f].error.mean, two.summaries[f].error.mean) << f;
  }
  EXPECT_NE(seif::paperSummaryText(stopped).find("Interrupted: 2 of 20 runs ran"), std::string::npos);
  EXPECT_EQ(seif::paperSummaryText(two).find("Interrupted"), std::string::npos);
  EXPECT_EQ(seif::interruptedText(stopped), "paper interrupted: 2 of 20 runs ran");
  const auto dir = seif::test::scratchDir("paper-interrupted");
  seif::writePaperResults(stopped, dir);
  const nlohmann::json j = nlohmann::json::parse(seif::test::slurp(dir / "results.json"));
  EXPECT_TRUE(j["setup"]["interrupted"].get<bool>());
  EXPECT_EQ(j["setup"]["runs_ok"], 2);
  request.stop = &stop;  // still set
  EXPECT_THROW(seif::runPaper(request), seif::Interrupted);
}

// One run gives no confidence interval: its cells print the mean alone (the paper's column
// keeps the paper's), where two runs print mean ± half-width.
TEST(PaperStudy, OneRunPrintsNoInterval) {
  auto intervals = [](int runs) {
    seif::PaperRequest request;
    request.runs = runs;
    request.options.steps = 60;
    const std::string text = seif::paperSummaryText(seif::runPaper(request));
    const std::size_t from = text.find("SEIF (constant time)");
    const std::string row = text.substr(from, text.find('\n', from) - from);
    std::size_t n = 0;
    for (std::size_t at = row.find("±"); at != std::string::npos; at = row.find("±", at + 1)) ++n;
    return std::pair{n, row};
  };
  const auto [one, row1] = intervals(1);
  EXPECT_EQ(one, 2u) << row1;  // the paper's error and links only
  EXPECT_NE(row1.find("6.35 ± 0.67"), std::string::npos) << row1;
  const auto [two, row2] = intervals(2);
  EXPECT_EQ(two, 5u) << row2;  // with the run's error, ratio and links
}

TEST(PaperExperiment, SnapshotOrdersByIdAndListsLinks) {
  seif::PaperOptions options;
  options.steps = 120;
  seif::PaperRunDetail detail;
  seif::runPaperExperiment(5, options, &detail);
  for (std::size_t f : {std::size_t{0}, std::size_t{2}}) {
    const seif::SlamFilter& filter = *detail.filters[f];
    const seif::FilterSnapshot s = seif::snapshotById(filter);
    ASSERT_EQ(s.ids.size(), filter.landmarkIds().size());
    EXPECT_TRUE(std::is_sorted(s.ids.begin(), s.ids.end()));
    for (std::size_t k = 0; k < s.ids.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(3 + 2 * k);
      EXPECT_NEAR((s.mean.segment<2>(i) - filter.landmark(s.ids[k])).norm(), 0.0, 1e-9);
      EXPECT_NEAR((s.covariance.block<2, 2>(i, i) - filter.landmarkCovariance(s.ids[k])).norm(), 0.0,
                  1e-9 * filter.landmarkCovariance(s.ids[k]).norm());
    }
    // The permuted matrices are still inverse to each other.
    const Eigen::MatrixXd I = s.covariance * s.information;
    EXPECT_LT((I - Eigen::MatrixXd::Identity(I.rows(), I.cols())).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_EQ(s.links.size(), filter.stats().links);
    std::size_t robot = 0;
    for (const auto& l : s.links) {
      robot += l.a < 0;
      EXPECT_GT(l.strength, 0.0);
      EXPECT_LE(l.strength, 1.0 + 1e-9);  // |H_ij| <= sqrt(H_ii H_jj) for H > 0
    }
    EXPECT_EQ(robot, filter.stats().robot_links);
  }
}

// ---------------------------------------------------------------- seif paper ----------

TEST(PaperCli, FourRunsEndToEnd) {
  const auto dir = scratchDir("paper-e2e");
  const fs::path out2 = dir / "jobs2", out1 = dir / "jobs1";
  const auto two = runCli("paper --runs 4 --jobs 2 --seed 11 --no-figures --out " + out2.string());
  ASSERT_EQ(two.status, 0) << two.out << two.err;
  const auto one = runCli("paper --runs 4 --jobs 1 --seed 11 --no-figures --out " + out1.string());
  ASSERT_EQ(one.status, 0) << one.out << one.err;
  const std::string& printed = two.out;
  EXPECT_NE(printed.find("final error"), std::string::npos) << printed;
  EXPECT_NE(printed.find("SEIF (constant time)"), std::string::npos) << printed;
  EXPECT_TRUE(fs::exists(out2 / "table.md"));
  EXPECT_NE(slurp(out2 / "table.md").find("| EKF |"), std::string::npos);
  EXPECT_FALSE(fs::exists(out2 / "fig1_ekf.png"));  // --no-figures
  EXPECT_TRUE(fs::exists(out2 / "figure_data" / "ekf.json"));

  const auto r2 = nlohmann::json::parse(slurp(out2 / "results.json"));
  const auto r1 = nlohmann::json::parse(slurp(out1 / "results.json"));
  ASSERT_TRUE(r2.contains("setup"));
  EXPECT_EQ(r2["setup"]["runs"], 4);
  EXPECT_EQ(r2["setup"]["seed"], 11);
  EXPECT_EQ(r2["setup"]["landmarks"], 50);
  EXPECT_EQ(r2["setup"]["steps"], 500);
  EXPECT_TRUE(r2["setup"].contains("error_definition"));
  ASSERT_EQ(r2["filters"].size(), 3u);
  const std::vector<std::string> names = {"ekf", "seif_exact", "seif"};
  for (std::size_t f = 0; f < 3; ++f) {
    const auto& j = r2["filters"][f];
    EXPECT_EQ(j["name"], names[f]);
    for (const char* key : {"runs", "error_mean", "error_ci95", "links_mean", "links_ci95",
                            "us_per_update_median", "per_run"}) {
      EXPECT_TRUE(j.contains(key)) << names[f] << " lacks " << key;
    }
    EXPECT_EQ(j["runs"], 4);
    EXPECT_GT(j["error_mean"].get<double>(), 0.0);
    EXPECT_GE(j["error_ci95"].get<double>(), 0.0);
    EXPECT_GT(j["us_per_update_median"].get<double>(), 0.0);
    ASSERT_EQ(j["per_run"].size(), 4u);
    // Same seed, other --jobs: identical errors and links.
    EXPECT_EQ(j["error_mean"], r1["filters"][f]["error_mean"]);
    EXPECT_EQ(j["error_ci95"], r1["filters"][f]["error_ci95"]);
    EXPECT_EQ(j["links_mean"], r1["filters"][f]["links_mean"]);
    for (std::size_t r = 0; r < 4; ++r) {
      EXPECT_EQ(j["per_run"][r]["error"], r1["filters"][f]["per_run"][r]["error"]);
      EXPECT_EQ(j["per_run"][r]["seed"], 11 + r);
      // The best rigid alignment includes the identity: it can only lower the error.
      const double shape = j["per_run"][r]["aligned_error"].get<double>();
      EXPECT_GT(shape, 0.0);
      EXPECT_LE(shape, j["per_run"][r]["error"].get<double>() * (1.0 + 1e-12));
    }
    EXPECT_LE(j["aligned_error_mean"].get<double>(), j["error_mean"].get<double>());
  }
  // Per run: the EKF's information matrix is the full graph of its n mapped landmarks and
  // the robot, n(n+1)/2 links; the SEIFs keep at most half of that.
  for (std::size_t r = 0; r < 4; ++r) {
    const auto& ekf = r2["filters"][0]["per_run"][r];
    const double n = ekf["mapped"].get<double>();
    EXPECT_EQ(ekf["links"].get<double>(), n * (n + 1) / 2);
    for (std::size_t f = 1; f < 3; ++f) {
      const auto& s = r2["filters"][f]["per_run"][r];
      EXPECT_EQ(s["mapped"].get<double>(), n);
      EXPECT_LE(s["links"].get<double>(), 0.5 * n * (n + 1) / 2);
    }
  }
}

TEST(PaperCli, PathSelectsThePaperWorldsPath) {
  const auto dir = scratchDir("paper-path");
  const fs::path lawn = dir / "lawnmower", liss = dir / "lissajous";
  const auto first = runCli("paper --runs 1 --seed 3 --no-figures --out " + lawn.string());
  ASSERT_EQ(first.status, 0) << first.out << first.err;
  const auto second = runCli("paper --runs 1 --seed 3 --path lissajous --no-figures --out " + liss.string());
  ASSERT_EQ(second.status, 0) << second.out << second.err;
  const auto a = nlohmann::json::parse(slurp(lawn / "results.json"));
  const auto b = nlohmann::json::parse(slurp(liss / "results.json"));
  EXPECT_EQ(a["setup"]["path"], "lawnmower");  // the default
  EXPECT_EQ(b["setup"]["path"], "lissajous");
  EXPECT_NE(second.out.find("lissajous path"), std::string::npos) << second.out;
  // Same seed, other path: other data, so other errors.
  EXPECT_NE(a["filters"][0]["error_mean"], b["filters"][0]["error_mean"]);
  // An unknown path is a usage error (exit 1) naming the valid ones.
  const auto bad = runCli("paper --runs 1 --path spiral --no-figures --out " + (dir / "bad").string());
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("lissajous"), std::string::npos) << bad.out << bad.err;
}

TEST(PaperCli, SweepAddsItsSection) {
  const auto dir = scratchDir("paper-sweep");
  const auto run = runCli("paper --runs 2 --jobs 2 --sweep-active 4,10 --no-figures --out " + dir.string());
  ASSERT_EQ(run.status, 0) << run.out << run.err;
  const auto r = nlohmann::json::parse(slurp(dir / "results.json"));
  ASSERT_EQ(r["sweep_active"].size(), 2u);
  EXPECT_EQ(r["sweep_active"][0]["active"], 4);
  EXPECT_EQ(r["sweep_active"][1]["active"], 10);
  for (const auto& s : r["sweep_active"]) {
    for (const char* key : {"error_mean", "error_ci95", "us_per_update_median", "links_mean"}) {
      EXPECT_TRUE(s.contains(key)) << key;
    }
  }
  EXPECT_NE(slurp(dir / "table.md").find("theta_x"), std::string::npos);
  EXPECT_NE(runCli("paper --runs 2 --sweep-active 0 --out " + (dir / "bad").string()).status, 0);
}

TEST(PaperCli, FiltersBeyondThePaperGetTheirTableWithNees) {
  const auto dir = scratchDir("paper-beyond");
  const auto run =
      runCli("paper --runs 2 --filters ekf:linearization=fej,seif:sparsify=eseif,beta=4 --no-figures --out " +
             dir.string());
  ASSERT_EQ(run.status, 0) << run.out << run.err;
  const auto r = nlohmann::json::parse(slurp(dir / "results.json"));
  ASSERT_EQ(r["filters"].size(), 5u);  // the paper's three, then the two given
  EXPECT_EQ(r["filters"][4]["spec"], "seif:sparsify=eseif,beta=4");
  for (const auto& f : r["filters"]) EXPECT_GT(f["landmark_nees_mean"].get<double>(), 0.0) << f["name"];
  EXPECT_NE(slurp(dir / "table.md").find("| seif:sparsify=eseif,beta=4 |"), std::string::npos);
  EXPECT_NE(runCli("paper --runs 2 --filters seif:beta --out " + (dir / "bad").string()).status, 0);
}

}  // namespace
