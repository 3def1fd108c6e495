// The Victoria Park reader: events, conventions, noise, every malformed line, and the real
// folder when ../shared/data is present.
#include "../fuzz/fuzz_events.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include "io/victoria_park.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <set>

#include <unistd.h>

namespace {

using namespace seif;
namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
const fs::path kReal = fs::path(SEIF_SHARED_DATA_DIR) / "victoria-park";

VictoriaParkFiles smallFolder() {
  VictoriaParkFiles f;
  f.folder = "vp";
  f.text["controls.txt"] = "# time speed steering\n1.0 2.0 0.1\n1.025 2.0 0.1\n2.0 1.0 -0.1\n";
  f.text["tree_observations_associated_UTS.txt"] =
      "# time range angle id x y\n1.025 10.0 1.5707963267948966 7 0 0\n1.025 5.0 0.5 9 0 0\n1.5 8.0 2.0 7 0 0\n";
  f.text["gps.txt"] = "0.5 1 2\n1.5 3 4\n";
  return f;
}

std::vector<Event> drain(EventSource& s) {
  std::vector<Event> events;
  Event e;
  while (s.next(e)) events.push_back(e);
  return events;
}

TEST(VictoriaPark, EventsInTimeOrderWithTheLaserConventions) {
  const VictoriaParkFiles f = smallFolder();
  auto source = openVictoriaPark(f, {});
  const std::vector<Event> e = drain(*source);
  ASSERT_EQ(e.size(), 7u);
  EXPECT_EQ(std::get<GpsFix>(e[0]).position, Vec2(1, 2));
  EXPECT_EQ(std::get<ControlEvent>(e[1]).time, 1.0);
  const auto& u = std::get<AckermannControl>(std::get<ControlEvent>(e[1]).input);
  EXPECT_EQ(u.speed, 2.0);
  EXPECT_EQ(u.steering, 0.1);
  // At 1.025: the observations (grouped) before the control that starts there.
  const auto& obs = std::get<ObservationEvent>(e[2]);
  ASSERT_EQ(obs.observations.size(), 2u);
  EXPECT_EQ(obs.observations[0].landmark, 7);
  EXPECT_NEAR(obs.observations[0].z.y(), 0.0, 1e-15);  // pi/2 = straight ahead
  EXPECT_NEAR(obs.observations[1].z.y(), 0.5 - kPi / 2, 1e-15);  // right of the truck
  EXPECT_EQ(std::get<ControlEvent>(e[3]).time, 1.025);
  EXPECT_EQ(std::get<ObservationEvent>(e[4]).time, 1.5);
  EXPECT_EQ(std::get<GpsFix>(e[5]).time, 1.5);
  EXPECT_EQ(std::get<ControlEvent>(e[6]).time, 2.0);
  EXPECT_TRUE(source->info().has_gps);
  EXPECT_FALSE(source->info().has_groundtruth);
  EXPECT_EQ(source->progress(), 1.0);
}

TEST(VictoriaPark, AssociatedObservationsCarryTheirFeatureIdAsTruth) {
  const VictoriaParkFiles f = smallFolder();  // the source reads the files in place
  auto source = openVictoriaPark(f, {});
  for (const Event& e : drain(*source)) {
    if (const auto* o = std::get_if<ObservationEvent>(&e)) {
      for (const Observation& z : o->observations) EXPECT_EQ(z.truth, z.landmark);
    }
  }
  EXPECT_TRUE(source->dropped().empty());
}

DatasetOptions rawDetections() {
  DatasetOptions o;
  o.detections = Detections::Raw;
  return o;
}

/// smallFolder() with raw detections: at 1.025 the two UTS rows (one printed to fewer
/// decimals), a spurious tree and one 0.02 m off the UTS range's precision; at 1.5 none of
/// the UTS row (so it is left unmatched), at 1.75 a stamp the UTS file does not have.
VictoriaParkFiles rawFolder() {
  VictoriaParkFiles f = smallFolder();
  f.text["tree_detections.txt"] =
      "# time scan range angle diameter\n"
      "1.025 3 5.000000 0.50000000 0.2\n"          // UTS id 9 (listed second there)
      "1.025 3 20.000000 1.00000000 0.3\n"         // spurious
      "1.025 3 10.04 1.57079633 0.25\n"            // UTS id 7: 10.0 (+-0.05) vs 10.04 (+-0.005)
      "1.5 4 8.2 2.0 0.1\n"                        // 8.0 (+-0.05) vs 8.2 (+-0.05): not the same
      "1.75 5 6.0 3.141593 0.0\n";                  // pi within its printed precision
  return f;
}

TEST(VictoriaPark, RawDetectionsHaveNoLandmarkAndTheUtsIdOfTheSameDetectionAsTruth) {
  const VictoriaParkFiles files = rawFolder();
  auto source = openVictoriaPark(files, rawDetections());
  std::vector<ObservationEvent> scans;
  for (const Event& e : drain(*source)) {
    if (const auto* o = std::get_if<ObservationEvent>(&e)) scans.push_back(*o);
  }
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[0].time, 1.025);
  ASSERT_EQ(scans[0].observations.size(), 3u);
  for (const auto& s : scans) {
    for (const Observation& z : s.observations) EXPECT_EQ(z.landmark, kUnknownLandmark);
  }
  EXPECT_EQ(scans[0].observations[0].truth, 9);
  EXPECT_EQ(scans[0].observations[0].z, Vec2(5.0, 0.5 - kPi / 2));
  EXPECT_EQ(scans[0].observations[1].truth, kUnknownLandmark);
  EXPECT_EQ(scans[0].observations[2].truth, 7);
  EXPECT_EQ(scans[1].observations.at(0).truth, kUnknownLandmark);
  EXPECT_EQ(scans[2].observations.at(0).truth, kUnknownLandmark);
  EXPECT_EQ(scans[2].observations.at(0).z.y(), kPi / 2);  // clamped to pi: exactly pi/2
  EXPECT_EQ(source->dropped(), (std::map<std::string, std::size_t>{{"associated_rows_without_raw_detection", 1}}));

  // Without the UTS file: the same detections, no truth.
  VictoriaParkFiles f = rawFolder();
  f.text.erase("tree_observations_associated_UTS.txt");
  auto bare = openVictoriaPark(f, rawDetections());
  std::size_t n = 0;
  for (const Event& e : drain(*bare)) {
    if (const auto* o = std::get_if<ObservationEvent>(&e)) {
      for (const Observation& z : o->observations) {
        EXPECT_EQ(z.truth, kUnknownLandmark);
        ++n;
      }
    }
  }
  EXPECT_EQ(n, 5u);
  EXPECT_TRUE(bare->dropped().empty());
}

TEST(VictoriaPark, EachFileIsRequiredOnlyWhereItIsRead) {
  const auto missing = [](VictoriaParkFiles f, const DatasetOptions& o, const char* name) {
    f.text.erase(name);
    try {
      openVictoriaPark(f, o);
      ADD_FAILURE() << "opened without " << name;
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("vp/") + name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("missing required file"), std::string::npos) << e.what();
    }
  };
  missing(rawFolder(), rawDetections(), "tree_detections.txt");
  missing(rawFolder(), rawDetections(), "controls.txt");
  missing(rawFolder(), {}, "tree_observations_associated_UTS.txt");
  VictoriaParkFiles f = rawFolder();
  f.text.erase("tree_detections.txt");
  EXPECT_NO_THROW(openVictoriaPark(f, {}));  // associated: the raw file is not needed

  // A folder is Victoria Park with controls.txt and either detections file.
  const fs::path dir = fs::temp_directory_path() / ("seif-vp-layout-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "controls.txt") << "1 0 0\n";
  EXPECT_FALSE(looksLikeVictoriaPark(dir));
  std::ofstream(dir / "tree_detections.txt") << "1 0 5 1 0.2\n";
  EXPECT_TRUE(looksLikeVictoriaPark(dir));
  EXPECT_EQ(openDataset(dir, DatasetFormat::Auto, rawDetections())->info().format, "victoria-park");
  fs::remove(dir / "tree_detections.txt");
  std::ofstream(dir / "tree_observations_associated_UTS.txt") << "1 5 1 3 0 0\n";
  EXPECT_TRUE(looksLikeVictoriaPark(dir));
  fs::remove_all(dir);
}

TEST(VictoriaPark, OptionsOfAnotherFormatAreAnInvalidArgument) {
  const fs::path file = fs::temp_directory_path() / ("seif-raw-isam-" + std::to_string(::getpid()) + ".txt");
  std::ofstream(file) << "ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-4\n";
  EXPECT_NO_THROW(openDataset(file));
  try {
    openDataset(file, DatasetFormat::Auto, rawDetections());
    ADD_FAILURE() << "raw detections from an iSAM file";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("Victoria Park folder only"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("isam"), std::string::npos) << e.what();
  }
  // So are the other options of one format only: a robot number, LANDMARK records read as
  // GTSAM reads them.
  DatasetOptions robot;
  robot.robot = 3;
  try {
    openDataset(file, DatasetFormat::Auto, robot);
    ADD_FAILURE() << "robot 3 of an iSAM file";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("robot number (3) selects one robot's log of an MRCLAM folder only"),
              std::string::npos)
        << e.what();
  }
  DatasetOptions gtsam;
  gtsam.isam_landmarks_as_gtsam = true;
  const fs::path park = fs::temp_directory_path() / ("seif-gtsam-park-" + std::to_string(::getpid()));
  fs::create_directories(park);
  std::ofstream(park / "controls.txt") << "1 0 0\n";
  std::ofstream(park / "tree_observations_associated_UTS.txt") << "1 5 1 3 0 0\n";
  EXPECT_NO_THROW(openDataset(park));
  EXPECT_THROW(openDataset(park, DatasetFormat::Auto, gtsam), InvalidArgument);
  EXPECT_THROW(openDataset(park, DatasetFormat::Auto, robot), InvalidArgument);
  fs::remove_all(park);
  fs::remove(file);
  EXPECT_EQ(parseDetections("raw"), Detections::Raw);
  EXPECT_EQ(detectionsName(Detections::Associated), "associated");
  EXPECT_THROW(parseDetections("unknown"), InvalidArgument);
}

/// The bearing read from a laser angle token, or the DataError's message.
std::string laserAngle(const std::string& token, const std::string& file, double* bearing) {
  VictoriaParkFiles f = rawFolder();
  DatasetOptions o;
  if (file == "tree_detections.txt") {
    f.text[file] = "1.025 3 5.0 " + token + " 0.2\n";
    o = rawDetections();
  } else {
    f.text[file] = "1.025 5.0 " + token + " 3 0 0\n";
  }
  try {
    auto source = openVictoriaPark(f, o);
    for (const Event& e : drain(*source)) {
      if (const auto* obs = std::get_if<ObservationEvent>(&e)) *bearing = obs->observations.at(0).z.y();
    }
    return {};
  } catch (const DataError& e) {
    return e.what();
  }
}

TEST(VictoriaPark, ALaserAngleWithinItsPrintedPrecisionOfTheFieldOfViewIsClamped) {
  for (const char* file : {"tree_observations_associated_UTS.txt", "tree_detections.txt"}) {
    double b = 1.0;
    EXPECT_EQ(laserAngle("3.141593", file, &b), "") << file;  // pi to 6 decimals: 3.46e-7 > pi
    EXPECT_EQ(b, kPi / 2) << file;                             // clamped: exactly pi/2
    b = 1.0;
    EXPECT_EQ(laserAngle("3.1416", file, &b), "") << file;  // 7.3e-6 above pi, within 5e-5
    EXPECT_EQ(b, kPi / 2) << file;
    b = 1.0;
    EXPECT_EQ(laserAngle("-0.000000", file, &b), "") << file;
    EXPECT_EQ(b, -kPi / 2) << file;
    b = 1.0;
    EXPECT_EQ(laserAngle("0.0031416e3", file, &b), "") << file;  // 3.1416 again: the exponent counts
    EXPECT_EQ(b, kPi / 2) << file;
    // Beyond the printed precision: refused, naming file and line.
    for (const char* token : {"3.15", "3.1415935", "-0.0000001", "3.2e0", "-0.4"}) {
      const std::string msg = laserAngle(token, file, &b);
      EXPECT_NE(msg.find(std::string("vp/") + file + ":1"), std::string::npos) << token << ": " << msg;
      EXPECT_NE(msg.find("outside [0, pi]"), std::string::npos) << token << ": " << msg;
    }
  }
}

TEST(VictoriaPark, MalformedRawLinesNameFileAndLine) {
  const auto refused = [](const std::string& content, const std::string& where, const std::string& what) {
    VictoriaParkFiles f = rawFolder();
    f.text["tree_detections.txt"] = content;
    try {
      auto source = openVictoriaPark(f, rawDetections());
      drain(*source);
      ADD_FAILURE() << "accepted: " << content;
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused("1.0 0 5 1 0.2\n1.1 1 5 1\n", "vp/tree_detections.txt:2", "expected 5 fields");
  refused("1.0 0 5 1 -0.2\n", "vp/tree_detections.txt:1", "diameter");
  refused("1.0 0 5 1 nan\n", "vp/tree_detections.txt:1", "non-finite");
  refused("1.0 -1 5 1 0.2\n", "vp/tree_detections.txt:1", "bad id");
  refused("1.0 0 0 1 0.2\n", "vp/tree_detections.txt:1", "range");
  refused("2.0 0 5 1 0.2\n1.0 1 5 1 0.2\n", "vp/tree_detections.txt:2", "goes backwards");
  refused("1.0 3 5 1 0.2\n1.0 4 6 1 0.2\n", "vp/tree_detections.txt:2", "scan index 4 differs from the 3");
  refused("1.0 3 5 1 0.2\n1.1 3 6 1 0.2\n", "vp/tree_detections.txt:2", "scan index 3 does not follow");
  // The UTS file, read for truth, keeps its checks.
  VictoriaParkFiles f = rawFolder();
  f.text["tree_observations_associated_UTS.txt"] = "1.025 5.0 0.5 9 0 0\n1.025 -5.0 0.5 9 0 0\n";
  try {
    auto source = openVictoriaPark(f, rawDetections());
    drain(*source);
    ADD_FAILURE() << "a negative range in the UTS file";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("tree_observations_associated_UTS.txt:2"), std::string::npos) << e.what();
  }
}

TEST(VictoriaPark, NoiseDefaultsAndOverridesSayWhereTheyCameFrom) {
  const VictoriaParkFiles f = smallFolder();
  DatasetOptions o;
  o.noise["sigma_range"] = 0.7;
  auto source = openVictoriaPark(f, o);
  std::map<std::string, NoiseSetting> n;
  for (const NoiseSetting& s : source->info().noise) n[s.name] = s;
  ASSERT_EQ(n.size(), 4u);
  EXPECT_EQ(n["sigma_range"].value, 0.7);
  EXPECT_EQ(n["sigma_range"].source, "command line");
  EXPECT_EQ(n["sigma_speed"].source, "default for victoria-park");
  EXPECT_EQ(n["sigma_speed"].unit, "m/s*sqrt(s)");
  o.noise["sigma_v"] = 0.1;  // a velocity-model name: not this format's
  EXPECT_THROW(openVictoriaPark(f, o), seif::InvalidArgument);
}

void expectDataError(const std::string& file, const std::string& content, const std::string& where,
                     const std::string& what) {
  VictoriaParkFiles f = smallFolder();
  f.text[file] = content;
  try {
    auto source = openVictoriaPark(f, {});
    drain(*source);
    ADD_FAILURE() << "accepted: " << content;
  } catch (const DataError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(where), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

TEST(VictoriaPark, MalformedLinesNameFileAndLine) {
  expectDataError("controls.txt", "1.0 2.0 0.1\n1.5 2.0\n", "vp/controls.txt:2", "expected 3 fields");
  expectDataError("controls.txt", "1.0 nan 0.1\n", "vp/controls.txt:1", "non-finite");
  expectDataError("controls.txt", "1.0 abc 0.1\n", "vp/controls.txt:1", "bad number 'abc'");
  expectDataError("controls.txt", "2.0 1 0\n1.0 1 0\n", "vp/controls.txt:2", "goes backwards");
  expectDataError("controls.txt", "1.0 1 2.0\n", "vp/controls.txt:1", "steering");
  expectDataError("controls.txt", "1.0 1e300 0.1\n", "vp/controls.txt:1", "speed 1e+300 m/s is beyond 10^3 m/s");
  expectDataError("tree_observations_associated_UTS.txt", "1.0 -1 1.0 3 0 0\n",
                  "tree_observations_associated_UTS.txt:1", "range");
  expectDataError("tree_observations_associated_UTS.txt", "1.0 4 3.5 3 0 0\n",
                  "tree_observations_associated_UTS.txt:1", "outside [0, pi]");
  expectDataError("tree_observations_associated_UTS.txt", "1.0 4 1.0 3.5 0 0\n",
                  "tree_observations_associated_UTS.txt:1", "bad id");
  expectDataError("gps.txt", "1 2 3\n0.5 2 3\n", "vp/gps.txt:2", "goes backwards");
  VictoriaParkFiles f = smallFolder();
  f.text.erase("controls.txt");
  EXPECT_THROW(openVictoriaPark(f, {}), DataError);
}

TEST(VictoriaPark, TheRealFolder) {
  if (!looksLikeVictoriaPark(kReal)) GTEST_SKIP() << "Victoria Park not found at " << kReal.string() << " (../shared/data)";
  auto source = openVictoriaPark(kReal, {});
  std::size_t controls = 0, observations = 0, instants = 0, fixes = 0;
  std::set<int> trees;
  double previous = -1e300, first = 0, last = 0;
  Pose2 x = Pose2::Zero();
  double path = 0.0, now = 0.0;
  AckermannControl u{};
  Event e;
  while (source->next(e)) {
    const double t = eventTime(e);
    ASSERT_GE(t, previous);
    previous = t;
    if (auto* c = std::get_if<ControlEvent>(&e)) {
      if (controls++ == 0) {
        first = t;
      } else {  // dead reckoning with the model itself
        u.dt = t - now;
        const Pose2 next = source->info().motion->apply(x, MotionInput(u));
        path += (next - x).head<2>().norm();
        x = next;
      }
      u = std::get<AckermannControl>(c->input);
      now = last = t;
    } else if (auto* o = std::get_if<ObservationEvent>(&e)) {
      ++instants;
      observations += o->observations.size();
      for (const Observation& z : o->observations) trees.insert(z.landmark);
    } else if (std::holds_alternative<GpsFix>(e)) {
      ++fixes;
    }
  }
  EXPECT_EQ(controls, 61945u);
  EXPECT_EQ(observations, 46860u);
  EXPECT_EQ(instants, 7122u);  // laser scans with at least one associated tree
  EXPECT_EQ(fixes, 4466u);
  EXPECT_EQ(trees.size(), 299u);
  EXPECT_NEAR(last - first, 1548.6, 0.1);  // the 26 minutes of the README
  EXPECT_GT(path, 3000.0);  // ~4 km driven (README)
  EXPECT_LT(path, 5000.0);
}

// The raw detections of the real folder: both files carry the laser scan's stamp, and every
// UTS row is one of the raw detections of its scan, printed alike (88.5 % of the raw
// detections get a truth id; the others are spurious or trees UTS did not associate).
TEST(VictoriaPark, TheRealFolderRawDetectionsAndTheirTruth) {
  if (!fs::exists(kReal / "tree_detections.txt")) GTEST_SKIP() << "Victoria Park not found at " << kReal.string();
  std::map<int, std::size_t> associated, raw;
  {
    auto source = openVictoriaPark(kReal, {});
    Event e;
    while (source->next(e)) {
      if (const auto* o = std::get_if<ObservationEvent>(&e)) {
        for (const Observation& z : o->observations) ++associated[z.truth];
      }
    }
  }
  auto source = openVictoriaPark(kReal, rawDetections());
  std::size_t detections = 0, scans = 0, controls = 0;
  Event e;
  while (source->next(e)) {
    if (const auto* o = std::get_if<ObservationEvent>(&e)) {
      ++scans;
      for (const Observation& z : o->observations) {
        ASSERT_EQ(z.landmark, kUnknownLandmark);
        ++raw[z.truth];
        ++detections;
      }
    } else if (std::holds_alternative<ControlEvent>(e)) {
      ++controls;
    }
  }
  EXPECT_EQ(controls, 61945u);
  EXPECT_EQ(scans, 7230u);  // of the 7249 laser scans, 19 have no detection
  EXPECT_EQ(detections, 52974u);
  EXPECT_EQ(raw[kUnknownLandmark], 52974u - 46860u);
  raw.erase(kUnknownLandmark);
  EXPECT_EQ(raw, associated);  // every UTS row matched once: the same sightings per tree
  EXPECT_EQ(raw.size(), 299u);
  EXPECT_EQ(source->dropped().at("associated_rows_without_raw_detection"), 0u);
}

// Every input kept for the fuzzer (seed corpus and past findings) is read to the end or
// refused with a printable DataError, and every event keeps the readers' promises.
TEST(VictoriaPark, FuzzInputsAreReadOrRefusedCleanly) {
  constexpr const char* kFiles[] = {"controls.txt", "tree_observations_associated_UTS.txt", "gps.txt",
                                    "tree_detections.txt"};
  std::size_t inputs = 0;
  for (const char* kind : {"regressions", "corpus"}) {
    for (const auto& entry : fs::directory_iterator(fs::path(SEIF_SOURCE_DIR) / "fuzz" / kind / "fuzz_victoria_park")) {
      std::ifstream in(entry.path(), std::ios::binary);
      const std::string input((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      VictoriaParkFiles files;
      files.folder = "fuzz";
      files.text = fuzz::splitFiles(input, kFiles);
      std::vector<DatasetOptions> options(1);  // as the fuzz target: raw too when the raw file is there
      if (files.text.count("tree_detections.txt") != 0) options.push_back(rawDetections());
      for (const DatasetOptions& o : options) {
        try {
          auto source = openVictoriaPark(files, o);
          Event e;
          double previous = -INFINITY;
          while (source->next(e)) {
            ASSERT_EQ(fuzz::brokenEvent(e, previous), "") << entry.path();
            previous = eventTime(e);
          }
        } catch (const DataError& e) {
          EXPECT_TRUE(fuzz::printable(e.what())) << entry.path();
        }
      }
      ++inputs;
    }
  }
  EXPECT_GE(inputs, 7u);
}

}  // namespace
