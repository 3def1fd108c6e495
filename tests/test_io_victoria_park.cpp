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

// Every input kept for the fuzzer (seed corpus and past findings) is read to the end or
// refused with a printable DataError, and every event keeps the readers' promises.
TEST(VictoriaPark, FuzzInputsAreReadOrRefusedCleanly) {
  constexpr const char* kFiles[] = {"controls.txt", "tree_observations_associated_UTS.txt", "gps.txt"};
  std::size_t inputs = 0;
  for (const char* kind : {"regressions", "corpus"}) {
    for (const auto& entry : fs::directory_iterator(fs::path(SEIF_SOURCE_DIR) / "fuzz" / kind / "fuzz_victoria_park")) {
      std::ifstream in(entry.path(), std::ios::binary);
      const std::string input((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      VictoriaParkFiles files;
      files.folder = "fuzz";
      files.text = fuzz::splitFiles(input, kFiles);
      try {
        auto source = openVictoriaPark(files, {});
        Event e;
        double previous = -INFINITY;
        while (source->next(e)) {
          ASSERT_EQ(fuzz::brokenEvent(e, previous), "") << entry.path();
          previous = eventTime(e);
        }
      } catch (const DataError& e) {
        EXPECT_TRUE(fuzz::printable(e.what())) << entry.path();
      }
      ++inputs;
    }
  }
  EXPECT_GE(inputs, 6u);
}

}  // namespace
