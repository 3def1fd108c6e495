// A run stopped early (RunRequest::stop; Ctrl-C or SIGTERM in `seif run`) writes its outputs
// for the steps it ran, says so in metrics.json, saves a checkpoint when given a file, and that
// checkpoint resumes to the outputs of the run never stopped.
#include "cli_support.hpp"
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <tuple>

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::writePaperWorld;
using seif::test::estimateMetrics;
using seif::test::slurp;

namespace {


void expectSameOutputs(const fs::path& a, const fs::path& b) {
  for (const char* file :
       {"trajectory.tum", "dead_reckoning.tum", "map.csv", "groundtruth.tum", "landmarks_groundtruth.csv"}) {
    EXPECT_TRUE(fs::exists(a / file) && fs::exists(b / file)) << file;  // simulated worlds: ground truth too
    EXPECT_EQ(slurp(a / file), slurp(b / file)) << file;
  }
  EXPECT_EQ(estimateMetrics(a), estimateMetrics(b));
}

TEST(RunStop, AStoppedRunWritesWhatItRanAndItsCheckpointResumesToTheWholeRun) {
  const auto dir = scratchDir("run-stop");
  const fs::path data = writePaperWorld(dir, 3000);  // progress is reported every 1024 steps
  for (const char* filter : {"seif", "ekf"}) {
    SCOPED_TRACE(filter);
    seif::RunRequest request;
    request.dataset = data;
    request.filter = filter;
    const fs::path whole = dir / (std::string(filter) + "-whole");
    fs::create_directories(whole);
    const seif::RunReport full = seif::runDataset(request, whole);
    EXPECT_FALSE(full.output.interrupted);
    EXPECT_FALSE(estimateMetrics(whole).at("interrupted").get<bool>());

    // Stopped from the second progress report on (after step 1024), with a checkpoint file
    // and no periodic checkpoints.
    std::atomic<bool> stop{false};
    int reports = 0;
    request.stop = &stop;
    request.checkpoint = dir / (std::string(filter) + ".ckpt");
    const fs::path part = dir / (std::string(filter) + "-part");
    fs::create_directories(part);
    const seif::RunReport stopped = seif::runDataset(request, part, [&](double) {
      if (++reports == 2) stop.store(true);
    });
    EXPECT_TRUE(stopped.output.interrupted);
    EXPECT_EQ(stopped.output.steps, 1025u);
    EXPECT_EQ(stopped.output.trajectory.size(), 1026u);
    const nlohmann::json metrics = estimateMetrics(part);
    EXPECT_TRUE(metrics.at("interrupted").get<bool>());
    EXPECT_EQ(metrics.at("steps").get<std::size_t>(), 1025u);
    // The trajectory written is the whole run's first 1026 poses.
    const std::string a = slurp(part / "trajectory.tum"), b = slurp(whole / "trajectory.tum");
    ASSERT_LT(a.size(), b.size());
    EXPECT_EQ(a, b.substr(0, a.size()));

    // The checkpoint saved where it stopped resumes to the whole run's outputs.
    seif::RunRequest resume;
    resume.dataset = data;
    resume.resume = request.checkpoint;
    const fs::path resumed = dir / (std::string(filter) + "-resumed");
    fs::create_directories(resumed);
    const seif::RunReport rest = seif::runDataset(resume, resumed);
    EXPECT_FALSE(rest.output.interrupted);
    expectSameOutputs(resumed, whole);
  }
}

// The same with data association: the checkpoint carries the associator (its index,
// provisional landmarks, held estimates and tallies), and the resumed run scores the same.
TEST(RunStop, AnAssociatingRunStoppedAndResumedEqualsTheWholeRun) {
  const auto dir = scratchDir("run-stop-association");
  seif::WorldConfig world = seif::presetConfig(seif::WorldPreset::Park, 0, 1600, 2);
  world.clutter = 1.0;
  world.detection_probability = 0.9;
  const fs::path data = dir / "data";
  seif::writeMrclam(data, seif::simulate(world));
  for (const auto& [filter, method, place] :
       {std::tuple{"seif", seif::AssociationMethod::NearestNeighbour, seif::ProvisionalPlace::Filter},
        std::tuple{"ekf", seif::AssociationMethod::Jcbb, seif::ProvisionalPlace::Held}}) {
    SCOPED_TRACE(filter);
    seif::RunRequest request;
    request.dataset = data;
    request.filter = filter;
    request.association.method = method;
    request.association.provisional = place;
    request.association.marginal = std::string(filter) == "seif" ? seif::MarginalMode::Local : seif::MarginalMode::Exact;
    const fs::path whole = dir / (std::string(filter) + "-whole");
    fs::create_directories(whole);
    seif::runDataset(request, whole);

    std::atomic<bool> stop{false};
    request.stop = &stop;
    request.checkpoint = dir / (std::string(filter) + ".ckpt");
    const fs::path part = dir / (std::string(filter) + "-part");
    fs::create_directories(part);
    int reports = 0;  // stopped at the second progress report, after step 1024
    const seif::RunReport stopped = seif::runDataset(request, part, [&](double) {
      if (++reports == 2) stop.store(true);
    });
    ASSERT_TRUE(stopped.output.interrupted);
    EXPECT_EQ(stopped.output.steps, 1025u);
    ASSERT_GT(stopped.association->new_landmarks, 0u);  // stopped with a map and provisional landmarks
    // A stop also stops the removal of the provisional landmarks in the filter: they stay in
    // the stopped run's map, counted (held ones are only forgotten).
    if (place == seif::ProvisionalPlace::Filter) {
      EXPECT_GT(stopped.association->provisional_final, 0u);
    } else {
      EXPECT_EQ(stopped.association->provisional_final, 0u);
    }
    EXPECT_EQ(stopped.landmarks, stopped.association->landmarks_final);

    seif::RunRequest resume;  // the association comes with the checkpoint
    resume.dataset = data;
    resume.resume = request.checkpoint;
    const fs::path resumed = dir / (std::string(filter) + "-resumed");
    fs::create_directories(resumed);
    const seif::RunReport rest = seif::runDataset(resume, resumed);
    EXPECT_EQ(rest.association_options.method, method);
    expectSameOutputs(resumed, whole);
    // Every observation's association too, those before the stop from the checkpoint.
    ASSERT_TRUE(fs::exists(whole / "associations.csv"));
    EXPECT_EQ(slurp(resumed / "associations.csv"), slurp(whole / "associations.csv"));
    EXPECT_EQ(rest.output.associations.size(), rest.association->observations);
    // The request named no association; the summary lists the file the checkpoint's wrote.
    const std::string summary = seif::runSummary(resume, rest, resumed);
    EXPECT_NE(summary.find(",associations.csv"), std::string::npos) << summary;
    EXPECT_EQ(summary.find("no associations.csv"), std::string::npos) << summary;
    EXPECT_GT(estimateMetrics(whole).at("association").at("correct").get<std::size_t>(), 0u);
  }
}

// A stop that comes after the last step, while the associator removes the provisional
// landmarks left: they stay in the map, the run is interrupted there, and its checkpoint
// finishes the removals when resumed.
TEST(RunStop, AStopDuringTheFinalRemovalsIsAnInterruptionThatResumes) {
  const auto dir = scratchDir("run-stop-final");
  seif::WorldConfig world = seif::presetConfig(seif::WorldPreset::Park, 0, 1025, 2);
  world.clutter = 1.0;
  world.detection_probability = 0.9;
  seif::RunRequest request;
  request.dataset = dir / "data";
  seif::writeMrclam(request.dataset, seif::simulate(world));
  request.filter = "seif";
  request.association.method = seif::AssociationMethod::NearestNeighbour;
  request.association.marginal = seif::MarginalMode::Local;
  const fs::path whole = dir / "whole";
  fs::create_directories(whole);
  const seif::RunReport full = seif::runDataset(request, whole);
  ASSERT_EQ(full.output.steps, 1025u);
  ASSERT_GT(full.association->provisional_removed, 0u);

  std::atomic<bool> stop{false};
  request.stop = &stop;
  request.checkpoint = dir / "run.ckpt";
  const fs::path part = dir / "part";
  fs::create_directories(part);
  int reports = 0;  // the second progress report comes after step 1024, the last
  const seif::RunReport stopped = seif::runDataset(request, part, [&](double) {
    if (++reports == 2) stop.store(true);
  });
  EXPECT_TRUE(stopped.output.interrupted);
  EXPECT_EQ(stopped.output.steps, 1025u);
  EXPECT_GT(stopped.association->provisional_final, 0u);
  EXPECT_EQ(stopped.landmarks, full.landmarks + stopped.association->provisional_final);
  EXPECT_TRUE(estimateMetrics(part).at("interrupted").get<bool>());

  seif::RunRequest resume;
  resume.dataset = request.dataset;
  resume.resume = request.checkpoint;
  const fs::path resumed = dir / "resumed";
  fs::create_directories(resumed);
  const seif::RunReport rest = seif::runDataset(resume, resumed);
  EXPECT_FALSE(rest.output.interrupted);
  expectSameOutputs(resumed, whole);
}

TEST(RunStop, AResumedRunReadsItsDatasetWithTheSameOptions) {
  const auto dir = scratchDir("run-stop-options");
  seif::RunRequest request;
  request.dataset = writePaperWorld(dir, 2000);
  std::atomic<bool> stop{false};
  request.stop = &stop;
  request.checkpoint = dir / "run.ckpt";
  const fs::path out = dir / "out";
  fs::create_directories(out);
  seif::runDataset(request, out, [&](double) { stop.store(true); });
  seif::RunRequest resume;
  resume.dataset = request.dataset;
  resume.resume = request.checkpoint;
  resume.dataset_options.noise["sigma_range"] = 0.5;  // other events than the checkpoint's run read
  try {
    seif::runDataset(resume, out);
    ADD_FAILURE() << "resumed with other dataset options";
  } catch (const seif::DataError& e) {
    EXPECT_NE(std::string(e.what()).find("sigma_range 0.5"), std::string::npos) << e.what();
  }
  // Association flags other than the checkpoint's are refused (its known association had
  // drop_unlabelled off; none given continues it).
  resume.dataset_options = {};
  resume.association.drop_unlabelled = true;
  EXPECT_THROW(seif::runDataset(resume, out), seif::InvalidArgument);
  resume.association.drop_unlabelled = false;
  resume.association.method = seif::AssociationMethod::NearestNeighbour;
  EXPECT_THROW(seif::runDataset(resume, out), seif::InvalidArgument);
}

TEST(RunStop, AStopBeforeTheFirstStepIsInterruptedAndWritesNothing) {
  const auto dir = scratchDir("run-stop-first");
  seif::RunRequest request;
  request.dataset = writePaperWorld(dir, 50);
  std::atomic<bool> stop{true};
  request.stop = &stop;
  const fs::path out = dir / "out";
  fs::create_directories(out);
  EXPECT_THROW(seif::runDataset(request, out), seif::Interrupted);
  EXPECT_FALSE(fs::exists(out / "metrics.json"));
}

TEST(RunStop, ACheckpointFileWithoutAPeriodIsWrittenOnlyWhenTheRunStops) {
  const auto dir = scratchDir("run-stop-period");
  seif::RunRequest request;
  request.dataset = writePaperWorld(dir, 200);
  request.checkpoint = dir / "run.ckpt";
  const fs::path out = dir / "out";
  fs::create_directories(out);
  seif::runDataset(request, out);
  EXPECT_FALSE(fs::exists(request.checkpoint));
  request.checkpoint.clear();
  request.checkpoint_every = 10;  // a period without a file is a bad request
  EXPECT_THROW(seif::runDataset(request, out), seif::InvalidArgument);
}

// `seif run` stopped by a signal: exit 130, one line on stderr saying how many steps ran and
// how to go on, the outputs of those steps written, and the checkpoint resumes to the whole
// run. The signal comes at 40 % of the whole run's wall time, measured here (the EKF over 300
// landmarks: 0.5-3 s in Release, as fast or slow as the machine), so that it lands mid-run;
// labelled slow (tests/CMakeLists.txt).
TEST(RunStopCli, SigtermAndSigintStopTheRunAndItsCheckpointResumes) {
  const auto dir = scratchDir("run-stop-cli");
  const fs::path data = dir / "data";
  ASSERT_EQ(runCli("simulate --preset uniform --landmarks 300 --seed 2 --out " + data.string()).status, 0);
  const std::string run = "run --dataset " + data.string() + " --filter ekf --map-covariance none";
  const auto started = std::chrono::steady_clock::now();
  const auto whole = runCli(run + " --out " + (dir / "whole").string());
  ASSERT_EQ(whole.status, 0) << whole.err;
  const double signal_after = 0.4 * std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const std::size_t total = estimateMetrics(dir / "whole").at("steps").get<std::size_t>();
  for (const char* signal : {"TERM", "INT"}) {
    SCOPED_TRACE(signal);
    const fs::path ckpt = dir / (std::string(signal) + ".ckpt"), part = dir / (std::string(signal) + "-part");
    const auto stopped =
        seif::test::runCliSignalled(run + " --checkpoint " + ckpt.string() + " --out " + part.string(), signal, signal_after);
    ASSERT_EQ(stopped.status, 130) << stopped.out << stopped.err;
    EXPECT_NE(stopped.err.find("run interrupted after "), std::string::npos) << stopped.err;
    EXPECT_NE(stopped.err.find("--resume " + ckpt.string()), std::string::npos) << stopped.err;
    EXPECT_NE(stopped.out.find("wrote " + part.string()), std::string::npos) << stopped.out;
    const nlohmann::json metrics = estimateMetrics(part);
    EXPECT_TRUE(metrics.at("interrupted").get<bool>());
    EXPECT_GT(metrics.at("steps").get<std::size_t>(), 0u);
    EXPECT_LT(metrics.at("steps").get<std::size_t>(), total);
    const auto resumed = runCli("run --dataset " + data.string() + " --resume " + ckpt.string() +
                                " --map-covariance none --out " + (dir / (std::string(signal) + "-resumed")).string());
    ASSERT_EQ(resumed.status, 0) << resumed.err;
    expectSameOutputs(dir / (std::string(signal) + "-resumed"), dir / "whole");
  }
}

}  // namespace
