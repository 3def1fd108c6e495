// The command-line tool end to end, as a user runs it.
#include "cli_support.hpp"
#include "scenario.hpp"
#include "options.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/stats.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

namespace {

using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;
using seif::test::writePaperWorld;
namespace fs = std::filesystem;

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

// --smooth reads each filter's landmark covariances against the batch MAP's (the honest
// reference under the same models). On the paper world the consistent profile claims about
// the batch's variance; the EKF a fifth of it; the paper SEIF under a tenth of the EKF's.
TEST(Cli, SmoothMeasuresTheFiltersCovariancesAgainstTheBatchs) {
  const auto dir = scratchDir("covariance-ratio");
  ASSERT_EQ(runCli("simulate --preset paper --seed 3 --out " + (dir / "W").string()).status, 0);
  std::map<std::string, double> median;
  for (const std::string f : {"ekf", "seif", "seif:profile=consistent"}) {
    const std::filesystem::path out = dir / (f == "ekf" ? "ekf" : f == "seif" ? "seif" : "profile");
    const auto r = runCli("run --dataset " + (dir / "W").string() + " --filter " + f + " --smooth --out " + out.string());
    ASSERT_EQ(r.status, 0) << r.err;
    const auto c = readJson(out / "metrics.json")["filter_before_smoothing"]["landmark_covariance_ratio_to_batch"];
    median[f] = c["median"].get<double>();
    EXPECT_LE(c["p10"].get<double>(), median[f]);
    EXPECT_LE(median[f], c["p90"].get<double>());
    // The same median from the two maps the run writes (cov_xx + cov_yy, rows by id).
    const auto batch = readRows(out / "map.csv", ',');
    const auto filter = readRows(out / "map_filter.csv", ',');
    ASSERT_EQ(batch.size(), filter.size());
    std::vector<double> ratios;
    for (std::size_t i = 0; i < batch.size(); ++i) {
      ASSERT_EQ(batch[i][0], filter[i][0]);
      ratios.push_back((filter[i][3] + filter[i][5]) / (batch[i][3] + batch[i][5]));
    }
    EXPECT_NEAR(seif::median(ratios), median[f], 1e-6 * median[f]) << f;
  }
  EXPECT_GT(median["seif:profile=consistent"], 0.6);
  EXPECT_LT(median["seif:profile=consistent"], 1.5);
  EXPECT_LT(median["ekf"], 0.5);
  EXPECT_LT(median["seif"], 0.1 * median["ekf"]);
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

// ---- every command-line input is checked where it enters ----------------------------------

namespace {

/// A command line that must be refused before any work: usage errors (bad flag values) exit
/// 1, an unusable --out exits 2, each with a message naming the flag or the path.
struct BadInput {
  const char* name;
  std::string args;     // {out}: a fresh path in a scratch folder; {file}: an existing file
  int status;
  std::string message;  // expected in stderr, with the same substitutions
};

void PrintTo(const BadInput& c, std::ostream* os) { *os << "seif " << c.args; }

void replaceAll(std::string& s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
}

// Cheap settings, so that a value wrongly accepted fails fast instead of running for hours.
const std::string kRun = "run --dataset / --out {out} ";
const std::string kSimulate = "simulate --out {out} ";
const std::string kPaper = "paper --runs 1 --no-figures --out {out} ";
const std::string kBench =
    "bench --filters seif --landmarks 100 --window 10 --repeat 1 --no-figure --out {out} ";
const std::string kInt = "must be an integer in [1, 2147483647], found ";
const std::string kSeed = "must be an integer in [0, 18446744073709551615], found ";

const std::vector<BadInput> kBadInputs = {
    // Noise sigmas (and bench's budgets): finite and > 0.
    {"run_sigma_v_nan", kRun + "--sigma-v nan", 1, "--sigma-v: must be finite and > 0, found nan"},
    {"run_sigma_w_inf", kRun + "--sigma-w inf", 1, "--sigma-w: must be finite and > 0, found inf"},
    {"run_sigma_range_zero", kRun + "--sigma-range 0", 1, "--sigma-range: must be finite and > 0, found 0"},
    {"run_sigma_bearing_negative", kRun + "--sigma-bearing -0.1", 1,
     "--sigma-bearing: must be finite and > 0, found -0.1"},
    {"run_sigma_v_overflow", kRun + "--sigma-v 1e999", 1, "--sigma-v: must be finite and > 0, found 1e999"},
    {"bench_max_seconds_nan", kBench + "--max-seconds nan", 1,
     "--max-seconds: must be finite and > 0, found nan"},
    {"bench_max_memory_inf", kBench + "--max-memory-gb inf", 1,
     "--max-memory-gb: must be finite and > 0, found inf"},
    // Seeds: integers in [0, 2^64 - 1], never wrapped or saturated.
    {"simulate_seed_negative", kSimulate + "--seed -1", 1, "--seed: " + kSeed + "-1"},
    {"simulate_seed_overflow", kSimulate + "--seed 99999999999999999999", 1,
     "--seed: " + kSeed + "99999999999999999999"},
    {"run_seed_negative", kRun + "--seed -1", 1, "--seed: " + kSeed + "-1"},
    {"paper_seed_negative", kPaper + "--seed -3", 1, "--seed: " + kSeed + "-3"},
    {"paper_seeds_past_2_64", "paper --runs 2 --no-figures --out {out} --seed 18446744073709551615", 1,
     "seed + runs - 1 (--seed, --runs) must be at most 18446744073709551615"},
    {"bench_seed_negative", kBench + "--seed -1", 1, "--seed: " + kSeed + "-1"},
    {"bench_world_seed_negative", kBench + "--world-seed -1", 1, "--world-seed: " + kSeed + "-1"},
    // --relax: an int >= 0.
    {"run_relax_overflow", kRun + "--relax 99999999999", 1,
     "--relax: must be an integer in [0, 2147483647], found 99999999999"},
    {"run_relax_negative", kRun + "--relax -1", 1,
     "--relax: must be an integer in [0, 2147483647], found -1"},
    {"run_relax_nan", kRun + "--relax nan", 1, "--relax: must be an integer in [0, 2147483647], found nan"},
    // The other integer flags.
    {"simulate_landmarks_nan", kSimulate + "--landmarks nan", 1, "--landmarks: " + kInt + "nan"},
    {"simulate_landmarks_overflow", kSimulate + "--landmarks 99999999999", 1,
     "--landmarks: " + kInt + "99999999999"},
    {"simulate_steps_inf", kSimulate + "--steps inf", 1, "--steps: " + kInt + "inf"},
    {"simulate_steps_negative", kSimulate + "--steps -5", 1, "--steps: " + kInt + "-5"},
    {"run_active_nan", kRun + "--active nan", 1, "--active: must be an integer in [1, 39], found nan"},
    {"run_active_too_many", kRun + "--active 40", 1, "--active: must be an integer in [1, 39], found 40"},
    {"run_robot_inf", kRun + "--robot inf", 1, "--robot: must be an integer in [1, 5], found inf"},
    {"run_outlier_gate_nan", kRun + "--outlier-gate nan", 1, "--outlier-gate: must be > 0 (or inf), found nan"},
    {"run_outlier_gate_zero", kRun + "--outlier-gate 0", 1, "--outlier-gate: must be > 0 (or inf), found 0"},
    {"paper_runs_nan", kPaper + "--runs nan", 1, "--runs: " + kInt + "nan"},
    {"paper_runs_overflow", kPaper + "--runs 99999999999", 1, "--runs: " + kInt + "99999999999"},
    {"paper_runs_negative", kPaper + "--runs -1", 1, "--runs: " + kInt + "-1"},
    {"paper_jobs_negative", kPaper + "--jobs -1", 1, "--jobs: " + kInt + "-1"},
    {"paper_jobs_inf", kPaper + "--jobs inf", 1, "--jobs: " + kInt + "inf"},
    {"paper_sweep_active_nan", kPaper + "--sweep-active 4,nan", 1,
     "--sweep-active: must be an integer in [1, 39], found nan"},
    {"paper_sweep_active_negative", kPaper + "--sweep-active 4,-6", 1,
     "--sweep-active: must be an integer in [1, 39], found -6"},
    {"bench_landmarks_nan", kBench + "--landmarks 100,nan", 1,
     "--landmarks: must be an integer in [1, 10000000], found nan"},
    {"bench_landmarks_overflow", kBench + "--landmarks 100,99999999999", 1,
     "--landmarks: must be an integer in [1, 10000000], found 99999999999"},
    {"bench_landmarks_negative", kBench + "--landmarks -5", 1,
     "--landmarks: must be an integer in [1, 10000000], found -5"},
    {"bench_window_overflow", kBench + "--window 99999999999", 1,
     "--window: must be an integer in [1, 1000000], found 99999999999"},
    {"bench_repeat_nan", kBench + "--repeat nan", 1, "--repeat: must be an integer in [1, 100], found nan"},
    {"bench_active_inf", kBench + "--active inf", 1, "--active: must be an integer in [1, 39], found inf"},
    // --out: checked before any work (a paper of 100000 runs would take hours; a uniform
    // world of 2^31-1 landmarks is refused by the simulator, after the --out check).
    {"run_out_empty", "run --dataset / --out ''", 1, "--out: must not be empty"},
    {"run_out_under_file", "run --dataset / --out {file}/sub", 2, "{file}/sub: cannot create folder"},
    {"run_out_is_file", "run --dataset / --out {file}", 2, "{file}: output path exists and is not a folder"},
    {"paper_out_empty", "paper --runs 100000 --out ''", 1, "--out: must not be empty"},
    {"paper_out_under_file", "paper --runs 100000 --out {file}/sub", 2, "{file}/sub: cannot create folder"},
    {"paper_out_is_file", "paper --runs 100000 --out {file}", 2,
     "{file}: output path exists and is not a folder"},
    {"bench_out_under_file", "bench --no-figure --out {file}/sub", 2, "{file}/sub: cannot create folder"},
    {"bench_out_is_file", "bench --no-figure --out {file}", 2,
     "{file}: output path exists and is not a folder"},
    {"simulate_out_under_file", "simulate --preset uniform --landmarks 2147483647 --out {file}/sub", 2,
     "{file}/sub: cannot create folder"},
    {"simulate_out_is_file", "simulate --preset uniform --landmarks 2147483647 --out {file}", 2,
     "{file}: output path exists and is not a folder"},
};

class CliInput : public ::testing::TestWithParam<BadInput> {};

}  // namespace

TEST_P(CliInput, IsRefusedBeforeAnyWork) {
  const BadInput& c = GetParam();
  const auto dir = scratchDir("input");
  std::ofstream(dir / "file") << "not a folder\n";
  auto substitute = [&](std::string s) {
    replaceAll(s, "{out}", (dir / "out").string());
    replaceAll(s, "{file}", (dir / "file").string());
    return s;
  };
  const auto r = runCli(substitute(c.args), 60);
  EXPECT_EQ(r.status, c.status) << r.err;
  EXPECT_NE(r.err.find(substitute(c.message)), std::string::npos) << r.err;
  EXPECT_LT(r.seconds, 20.0);
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  if (c.status == 2) {
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Flags, CliInput, ::testing::ValuesIn(kBadInputs),
                         [](const ::testing::TestParamInfo<BadInput>& p) {
                           return std::string(p.param.name);
                         });

// The flags' rule for the noise sigmas (finite and > 0) holds for the values a run ends up
// with, whichever their source: a dataset whose meta.json has a zero sigma is bad data.
TEST(Cli, ZeroNoiseFromTheDatasetIsRefused) {
  const auto dir = scratchDir("zero-noise");
  ASSERT_EQ(runCli("simulate --preset paper --steps 20 --seed 4 --out " + (dir / "W").string()).status, 0);
  auto meta = readJson(dir / "W" / "meta.json");
  meta["noise"]["sigma_v"] = 0.0;
  std::ofstream(dir / "W" / "meta.json") << meta.dump(2) << "\n";
  const auto r =
      runCli("run --dataset " + (dir / "W").string() + " --filter ekf --out " + (dir / "R").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("sigma_v"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  std::filesystem::remove_all(dir);
}

// Integers are read as decimal: CLI11 alone reads 010 as octal (8).
TEST(Cli, IntegerFlagsAreDecimal) {
  const auto dir = scratchDir("decimal");
  const auto r = runCli("simulate --preset paper --landmarks 010 --steps 010 --seed 010 --out " +
                        (dir / "W").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("10 landmarks, 10 steps, seed 10,"), std::string::npos) << r.out;
  std::filesystem::remove_all(dir);
}

// The same rule for the final noise values whichever their source (resolveNoise): the
// command line wins over the file, the file over the format's default, and a value that is
// not finite and > 0 is refused naming its source.
TEST(Cli, NoiseValuesResolveRequiresFinitePositiveSigmas) {
  seif::DatasetInfo info;
  info.format = "mrclam";
  seif::DatasetOptions options;
  EXPECT_EQ(seif::resolveNoise(info, options, "sigma_v", "m/s", 0.2, "meta.json", 0.05), 0.2);
  EXPECT_EQ(info.noise.back().source, "meta.json");
  EXPECT_EQ(seif::resolveNoise(info, options, "sigma_w", "rad/s", std::nullopt, "meta.json", 0.3), 0.3);
  EXPECT_EQ(info.noise.back().source, "default for mrclam");
  options.noise["sigma_v"] = 0.01;
  EXPECT_EQ(seif::resolveNoise(info, options, "sigma_v", "m/s", 0.2, "meta.json", 0.05), 0.01);
  EXPECT_EQ(info.noise.back().source, "command line");
  try {
    seif::resolveNoise(info, {}, "sigma_v", "m/s", 0.0, "meta.json", 0.05);
    ADD_FAILURE() << "a zero sigma was accepted";
  } catch (const seif::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("sigma_v must be finite and > 0, found 0 (meta.json)"), std::string::npos)
        << e.what();
  }
  options.noise["sigma_nope"] = 1.0;
  EXPECT_THROW(seif::checkNoiseNames(options, {"sigma_v"}, "mrclam"), seif::InvalidArgument);
}

TEST(Cli, FlagsTheFilterDoesNotTakeAreNoted) {
  // A SEIF option with the EKF, a batch option without the batch, an association tuning flag
  // with known association: each named on stderr, and the run is the one without them.
  const auto dir = scratchDir("ignored-flags");
  const fs::path data = writePaperWorld(dir, 40);
  const auto plain = runCli("run --dataset " + data.string() + " --filter ekf --out " + (dir / "a").string());
  ASSERT_EQ(plain.status, 0) << plain.err;
  const auto noted = runCli("run --dataset " + data.string() +
                            " --filter ekf --active 3 --solver kkt --accept-gate 0.9 --out " + (dir / "b").string());
  ASSERT_EQ(noted.status, 0) << noted.err;
  EXPECT_NE(noted.err.find("note: --active is a SEIF option: --filter ekf does not take it"), std::string::npos) << noted.err;
  EXPECT_NE(noted.err.find("note: --solver sets the batch MAP"), std::string::npos) << noted.err;
  EXPECT_NE(noted.err.find("note: --accept-gate tunes nn and jcbb"), std::string::npos) << noted.err;
  EXPECT_EQ(plain.err.find("note:"), std::string::npos) << plain.err;
  EXPECT_EQ(slurp(dir / "a" / "trajectory.tum"), slurp(dir / "b" / "trajectory.tum"));
  // Where they apply, no note.
  const auto seif = runCli("run --dataset " + data.string() + " --filter seif --active 3 --out " + (dir / "c").string());
  ASSERT_EQ(seif.status, 0) << seif.err;
  EXPECT_EQ(seif.err.find("note:"), std::string::npos) << seif.err;
  std::filesystem::remove_all(dir);
}

TEST(Cli, AssociationOnAClutteredWorld) {
  // Known association refuses a false detection and says how to go on; --drop-unlabelled
  // runs the known-association reference; nn with provisional landmarks held outside the
  // filter scores itself against the simulator's truth.
  const auto dir = scratchDir("association-run");
  ASSERT_EQ(runCli("simulate --preset park --steps 1500 --seed 3 --clutter 1 --detection-probability 0.9 --out " +
                   (dir / "W").string()).status, 0);
  const std::string data = " --dataset " + (dir / "W").string();
  const auto refused = runCli("run" + data + " --filter ekf --out " + (dir / "K0").string());
  EXPECT_NE(refused.status, 0);
  EXPECT_NE(refused.err.find("--drop-unlabelled"), std::string::npos) << refused.err;
  const auto known = runCli("run" + data + " --filter ekf --drop-unlabelled --out " + (dir / "K").string());
  ASSERT_EQ(known.status, 0) << known.err;
  const auto k = readJson(dir / "K" / "metrics.json");
  EXPECT_EQ(k["association"]["method"], "known");
  EXPECT_GT(k["association"]["unlabelled_dropped"].get<int>(), 0);
  const auto nn = runCli("run" + data + " --filter seif --association nn --gate-marginal local --provisional held --out " +
                         (dir / "N").string());
  ASSERT_EQ(nn.status, 0) << nn.err;
  const auto n = readJson(dir / "N" / "metrics.json");
  EXPECT_EQ(n["association"]["provisional"], "held");
  EXPECT_GT(n["association"]["correct_fraction"].get<double>(), 0.98);
  EXPECT_GT(n["association"]["provisional_removed"].get<int>(), 0);
  EXPECT_EQ(runCli("run" + data + " --filter ekf --association nn --provisional elsewhere --out " + (dir / "X").string()).status, 1);
  // Conservative gates keep the SEIF's covariance bounds, as the recorded spec says.
  const auto cons = runCli("run" + data + " --filter seif --association nn --gate-marginal conservative --out " +
                           (dir / "C").string());
  ASSERT_EQ(cons.status, 0) << cons.err;
  const auto c = readJson(dir / "C" / "metrics.json");
  EXPECT_NE(c["filter_spec"].get<std::string>().find("bounds=true"), std::string::npos) << c["filter_spec"];
  EXPECT_EQ(c["association"]["marginal"], "conservative");
  std::filesystem::remove_all(dir);
}
