// A run that fails part-way (a step's numerical failure, bad data further in the stream)
// keeps what it ran: the outputs of the steps before the failure are written, metrics.json
// names the failure, and the error is still reported (seif run: exit 2, one line). What an
// earlier run wrote into the folder never outlives a later one.
#include "cli_support.hpp"
#include "scenario.hpp"

#include <seif/association/association.hpp>
#include <seif/core/errors.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/filters/factory.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/sim/world.hpp>
#include "eval/run_checkpoint.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::writePaperWorld;
using seif::test::slurp;

namespace {

/// Adds a landmark (subject 56, barcode 156) seen twice at the stamp of the world's
/// `row`-th control (1-based, after the comment lines), at a range of 1e-300 m: the reader
/// takes it (a range > 0), the first sighting places it at the sensor, and the second is
/// predicted from there, a degenerate range-bearing prediction that fails the step. The steps
/// before it are the world's.
void degenerateSighting(const fs::path& data, int row) {
  std::istringstream odometry(slurp(data / "Robot1_Odometry.dat"));
  std::string stamp;
  int n = 0;
  for (std::string line; std::getline(odometry, line);) {
    if (!line.empty() && line[0] != '#' && ++n == row) stamp = line.substr(0, line.find('\t'));
  }
  std::ofstream(data / "Barcodes.dat", std::ios::app) << "56\t156\n";
  std::istringstream in(slurp(data / "Robot1_Measurement.dat"));
  std::string text;
  bool added = false;
  for (std::string line; std::getline(in, line);) {
    if (!added && !line.empty() && line[0] != '#' && std::stod(line) >= std::stod(stamp)) {
      text += stamp + "\t156\t1e-300\t0\n" + stamp + "\t156\t1e-300\t0.1\n";
      added = true;
    }
    text += line + "\n";
  }
  std::ofstream(data / "Robot1_Measurement.dat") << text;
}

}  // namespace

TEST(RunFailure, AStepThatFailsEndsTheRunWithTheOutputsOfTheStepsBeforeIt) {
  const auto dir = scratchDir("run-failure");
  const fs::path good = writePaperWorld(dir / "good", 200);
  const fs::path bad = writePaperWorld(dir / "bad", 200);
  degenerateSighting(bad, 120);
  for (const char* filter : {"seif", "ekf"}) {
    SCOPED_TRACE(filter);
    seif::RunRequest request;
    request.filter = filter;
    request.dataset = good;
    const fs::path whole = dir / (std::string(filter) + "-whole");
    fs::create_directories(whole);
    const seif::RunReport full = seif::runDataset(request, whole);
    EXPECT_FALSE(full.output.failure);

    request.dataset = bad;
    const fs::path part = dir / (std::string(filter) + "-part");
    fs::create_directories(part);
    const seif::RunReport failed = seif::runDataset(request, part);
    ASSERT_TRUE(failed.output.failure);
    EXPECT_THROW(std::rethrow_exception(failed.output.failure), seif::ModelError);  // the sighting, not the filter
    EXPECT_GT(failed.output.steps, 50u);
    EXPECT_LT(failed.output.steps, full.output.steps);
    const nlohmann::json metrics = nlohmann::json::parse(slurp(part / "metrics.json"));
    EXPECT_EQ(metrics.at("steps").get<std::size_t>(), failed.output.steps);
    EXPECT_NE(metrics.at("failure").get<std::string>().find("prediction is degenerate"), std::string::npos)
        << metrics.at("failure");
    EXPECT_TRUE(nlohmann::json::parse(slurp(whole / "metrics.json")).at("failure").is_null());
    // The trajectory written is the whole run's first poses, up to the failed step.
    const std::string a = slurp(part / "trajectory.tum"), b = slurp(whole / "trajectory.tum");
    ASSERT_LT(a.size(), b.size());
    EXPECT_EQ(a, b.substr(0, a.size()));
    EXPECT_TRUE(fs::exists(part / "map.csv"));
  }
  // The command line reports the run, then the failure: one line on stderr, exit status 2.
  const auto r = runCli("run --dataset " + bad.string() + " --filter ekf --out " + (dir / "cli").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("prediction is degenerate"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.out.find("the run failed at step"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(dir / "cli" / "trajectory.tum"));
  fs::remove_all(dir);
}

TEST(RunFailure, BadDataFurtherInTheStreamKeepsTheStepsBeforeItAndASmootherWritesNothing) {
  const auto dir = scratchDir("run-failure-data");
  const fs::path data = writePaperWorld(dir, 200);
  {  // a letter in the 150th odometry row
    std::istringstream in(slurp(data / "Robot1_Odometry.dat"));
    std::string line, text;
    int row = 0;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] != '#' && ++row == 150) line = line.substr(0, line.rfind('\t')) + "\t0.1x";
      text += line + "\n";
    }
    std::ofstream(data / "Robot1_Odometry.dat") << text;
  }
  seif::RunRequest request;
  request.dataset = data;
  request.filter = "ekf";
  request.trajectory_covariances = true;
  fs::create_directories(dir / "filter");
  const seif::RunReport r = seif::runDataset(request, dir / "filter");
  ASSERT_TRUE(r.output.failure);
  EXPECT_THROW(std::rethrow_exception(r.output.failure), seif::DataError);
  EXPECT_GT(r.output.steps, 100u);
  EXPECT_EQ(r.output.trajectory.size(), r.output.steps + 1);
  EXPECT_EQ(r.output.pose_covariances.size(), r.output.steps + 1);
  EXPECT_NE(nlohmann::json::parse(slurp(dir / "filter" / "metrics.json")).at("failure").get<std::string>().find(
                "Robot1_Odometry.dat:"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "filter" / "trajectory_cov.csv"));
  // A smoother's estimate is its solve at the end: it fails whole, writing nothing.
  request.smooth = true;
  request.trajectory_covariances = false;
  fs::create_directories(dir / "smooth");
  EXPECT_THROW(seif::runDataset(request, dir / "smooth"), seif::DataError);
  EXPECT_FALSE(fs::exists(dir / "smooth" / "metrics.json"));
  EXPECT_FALSE(fs::exists(dir / "smooth" / "trajectory.tum"));
  fs::remove_all(dir);
}

TEST(RunFailure, WhatAnEarlierRunWroteIsRemovedFirst) {
  const auto dir = scratchDir("run-stale");
  const fs::path data = writePaperWorld(dir, 50);
  const fs::path out = dir / "out";
  fs::create_directories(out);
  for (const char* stale : {"map_filter.csv", "trajectory_filter.tum", "gps.csv", "trajectory_cov.csv", "map.png"}) {
    std::ofstream(out / stale) << "from an earlier run\n";
  }
  std::ofstream(out / "notes.txt") << "the user's\n";
  seif::RunRequest request;
  request.dataset = data;
  seif::runDataset(request, out);
  for (const char* stale : {"map_filter.csv", "trajectory_filter.tum", "gps.csv", "trajectory_cov.csv", "map.png"}) {
    EXPECT_FALSE(fs::exists(out / stale)) << stale;
  }
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  fs::remove_all(dir);
}

TEST(RunFailure, ACheckpointIsNeverWrittenOverAFileThatIsNotOne) {
  // Given one of the dataset's own files by mistake, the run refuses before it starts, and
  // the file is left as it was; over an earlier checkpoint it writes.
  const auto dir = scratchDir("run-checkpoint-target");
  const fs::path data = writePaperWorld(dir, 40);
  const std::string odometry = slurp(data / "Robot1_Odometry.dat");
  seif::RunRequest request;
  request.dataset = data;
  request.checkpoint = data / "Robot1_Odometry.dat";
  request.checkpoint_every = 10;
  fs::create_directories(dir / "out");
  try {
    seif::runDataset(request, dir / "out");
    ADD_FAILURE() << "written over the odometry";
  } catch (const seif::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("Robot1_Odometry.dat exists and is not a seif checkpoint"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(slurp(data / "Robot1_Odometry.dat"), odometry);
  EXPECT_FALSE(fs::exists(dir / "out" / "metrics.json"));
  request.checkpoint = dir / "run.ckpt";
  seif::runDataset(request, dir / "out");
  ASSERT_TRUE(fs::exists(dir / "run.ckpt"));
  EXPECT_NO_THROW(seif::runDataset(request, dir / "out"));  // over its own checkpoint
  fs::remove_all(dir);
}

TEST(RunFailure, AResumedRunRefusesDataOtherThanTheCheckpointsOwn) {
  // The checkpoint records the digest of the steps it consumed: a control changed before the
  // resume point, or data cut short of it, is refused (the run's failure, exit 2), where the
  // same data resumes.
  const auto dir = scratchDir("run-resume-data");
  const fs::path data = writePaperWorld(dir, 60);
  const std::string odometry = slurp(data / "Robot1_Odometry.dat");
  seif::RunRequest request;
  request.dataset = data;
  request.checkpoint = dir / "run.ckpt";
  request.checkpoint_every = 40;
  fs::create_directories(dir / "a");
  seif::runDataset(request, dir / "a");
  seif::RunRequest resume;
  resume.dataset = data;
  resume.resume = request.checkpoint;
  fs::create_directories(dir / "b");
  EXPECT_FALSE(seif::runDataset(resume, dir / "b").output.failure);
  const auto expectRefused = [&](const std::string& what) {
    const seif::RunReport r = seif::runDataset(resume, dir / "b");
    ASSERT_TRUE(r.output.failure);
    try {
      std::rethrow_exception(r.output.failure);
    } catch (const seif::InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_EQ(r.output.steps, 40u);  // the checkpoint's, nothing run on the other data
  };
  // The odometry rewritten row by row: edit(row, line) changes a data row or drops it (false).
  const auto rewrite = [&](auto&& edit) {
    std::istringstream in(odometry);
    std::string text;
    int row = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#' || edit(++row, line)) text += line + "\n";
    }
    std::ofstream(data / "Robot1_Odometry.dat") << text;
  };
  rewrite([](int row, std::string& line) {  // the 10th control's speed changed
    const std::size_t v = line.find('\t') + 1;
    if (row == 10) line = line.substr(0, v) + "0.123456789" + line.substr(line.find('\t', v));
    return true;
  });
  expectRefused("steps differ from those the checkpoint consumed");
  rewrite([](int row, const std::string&) { return row <= 20; });  // cut to 20 controls
  expectRefused("it is not the data the checkpoint was written from");
  fs::remove_all(dir);
}

TEST(RunFailure, AResumedRunRefusesAnotherFilterAndSmoothing) {
  const auto dir = scratchDir("run-resume-conflicts");
  const fs::path data = writePaperWorld(dir, 60);
  seif::RunRequest request;
  request.dataset = data;
  request.filter = "seif:active=4";
  request.checkpoint = dir / "run.ckpt";
  request.checkpoint_every = 20;
  fs::create_directories(dir / "a");
  seif::runDataset(request, dir / "a");
  seif::RunRequest resume;
  resume.dataset = data;
  resume.resume = request.checkpoint;
  resume.filter = "ekf";
  fs::create_directories(dir / "b");
  EXPECT_THROW(seif::runDataset(resume, dir / "b"), seif::InvalidArgument);
  resume.filter = "seif:active=4";  // the checkpoint's own: accepted
  EXPECT_NO_THROW(seif::runDataset(resume, dir / "b"));
  const seif::RunRequest defaults;
  resume.filter = defaults.filter;  // another option given as a flag: refused
  resume.seif.active = 9;
  EXPECT_THROW(seif::runDataset(resume, dir / "b"), seif::InvalidArgument);
  resume.seif = defaults.seif;
  resume.smooth = true;
  EXPECT_THROW(seif::runDataset(resume, dir / "b"), seif::InvalidArgument);
  fs::remove_all(dir);
}

TEST(RunFailure, AnAssociationWindowThatCanNeverConfirmIsRefused) {
  seif::AssociationOptions o;
  o.method = seif::AssociationMethod::NearestNeighbour;
  o.confirm = 4;
  o.window = 2;
  EXPECT_THROW(seif::Associator{o}, seif::InvalidArgument);
  o.window = 3;
  EXPECT_NO_THROW(seif::Associator{o});
  o.confirm = 1;
  o.window = 0;
  EXPECT_NO_THROW(seif::Associator{o});
  o.confirm = 4;
  o.method = seif::AssociationMethod::Known;  // which uses neither
  EXPECT_NO_THROW(seif::Associator{o});
}

TEST(RunFailure, FilterSpecsRefuseRepeatedKeysEmptyItemsAndLists) {
  EXPECT_THROW(seif::parseFilterSpec("seif:active=4,active=5"), seif::InvalidArgument);
  EXPECT_THROW(seif::parseFilterSpec("seif:active=4,"), seif::InvalidArgument);
  EXPECT_THROW(seif::parseFilterSpec("seif:active=4,,relax=3"), seif::InvalidArgument);
  try {
    seif::parseFilterSpec("ekf,seif");
    ADD_FAILURE() << "a list was taken for one spec";
  } catch (const seif::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("a list where one filter spec is expected"), std::string::npos) << e.what();
  }
  EXPECT_EQ(seif::parseFilterSpec("seif:profile=consistent,active=20").seif.active, 20);
  EXPECT_THROW(seif::splitFilterList("ekf,,seif"), seif::InvalidArgument);
  EXPECT_THROW(seif::splitFilterList("ekf,seif,ekf"), seif::InvalidArgument);  // two rows alike
  EXPECT_EQ(seif::splitFilterList("ekf:linearization=invariant,iterations=2,ekf").size(), 2u);
  EXPECT_THROW(seif::splitFilterList(""), seif::InvalidArgument);
}

// A checkpoint's run outputs are checked as a run writes them, even where its checksum was
// forged: finite stamps in time order, finite step times.
TEST(RunFailure, ACheckpointsRunOutputsHoldFiniteOrderedStamps) {
  seif::RunOutput out;
  out.steps = 2;
  out.trajectory = {{0.0, seif::Pose2::Zero()}, {1.0, seif::Pose2::Zero()}, {2.0, seif::Pose2::Zero()}};
  out.dead_reckoning = out.trajectory;
  out.step_seconds = {1e-3, 1e-3};
  out.seconds = 2e-3;
  EXPECT_NO_THROW(seif::decodeRunOutput(seif::encodeRunOutput(out), "c"));
  seif::RunOutput bad = out;
  bad.trajectory[1].time = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(seif::decodeRunOutput(seif::encodeRunOutput(bad), "c"), seif::DataError);
  bad = out;
  bad.dead_reckoning[2].time = 0.5;  // back in time
  EXPECT_THROW(seif::decodeRunOutput(seif::encodeRunOutput(bad), "c"), seif::DataError);
  bad = out;
  bad.step_seconds[0] = -1.0;
  EXPECT_THROW(seif::decodeRunOutput(seif::encodeRunOutput(bad), "c"), seif::DataError);
}
