// The iSAM and g2o readers and writer: events, the id and time-order rules, every malformed
// line, the round trip on victoria_park.txt, and a run from either format.
#include "../fuzz/fuzz_events.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/filters/factory.hpp>
#include <seif/io/graph_file.hpp>

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>

namespace {

using namespace seif;
namespace fs = std::filesystem;
const fs::path kReal = fs::path(SEIF_SHARED_DATA_DIR) / "victoria-park-isam" / "victoria_park.txt";

std::vector<Event> drain(EventSource& s) {
  std::vector<Event> events;
  Event e;
  while (s.next(e)) events.push_back(e);
  return events;
}

const char* kIsam =
    "LANDMARK 10 50 1 2 0.4 0 0.4\n"
    "ODOMETRY 10 12 1.0 0.0 0.1 0.01 0 0 0.02 0 0.03\n"
    "LANDMARK 12 50 0.5 2.5 0.4 0.1 0.4\n"
    "LANDMARK 12 51 3 -1 0.2 0 0.2\n"
    "ODOMETRY 12 13 1.0 0.1 0.0 0.01 0 0 0.02 0 0.03\n";

TEST(GraphFile, IsamEventsPoseTimesAndOwnNoise) {
  auto s = openIsamText("f.txt", kIsam);
  const std::vector<Event> e = drain(*s);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(std::get<ObservationEvent>(e[0]).time, 0.0);  // from the chain's first pose
  const auto& c = std::get<ControlEvent>(e[1]);
  EXPECT_EQ(c.time, 1.0);
  EXPECT_EQ(c.pose, 12);
  EXPECT_EQ(std::get<OdometryIncrement>(c.input).covariance(2, 2), 0.03);
  const auto& o = std::get<ObservationEvent>(e[2]);
  ASSERT_EQ(o.observations.size(), 2u);
  EXPECT_EQ(o.observations[0].landmark, 50);
  EXPECT_EQ((*o.observations[0].noise)(0, 1), 0.1);
  EXPECT_EQ(o.observations[1].z, Vec2(3, -1));
  EXPECT_EQ(std::get<ControlEvent>(e[3]).time, 2.0);
  EXPECT_EQ(s->info().start_pose_id, 10);
  EXPECT_EQ(s->info().format, "isam");
  ASSERT_EQ(s->info().noise.size(), 2u);  // each record carries its own: no one value
  for (const NoiseSetting& n : s->info().noise) EXPECT_FALSE(n.value) << n.name;
}

TEST(GraphFile, G2oTakesItsStartPoseFromTheFirstVertexAndInvertsInformation) {
  const char* g2o =
      "VERTEX_SE2 0 1 2 0.5\nVERTEX_SE2 1 2 2 0.5\nEDGE_SE2 0 1 1 0 0 100 0 0 100 0 1000\n"
      "VERTEX_XY 7 3 3\nEDGE_SE2_XY 1 7 1 1 4 0 4\n";
  auto s = openG2oText("f.g2o", g2o);
  const std::vector<Event> e = drain(*s);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(s->info().start_pose, Pose2(1, 2, 0.5));
  EXPECT_EQ(std::get<OdometryIncrement>(std::get<ControlEvent>(e[0]).input).covariance(2, 2), 1e-3);
  EXPECT_EQ((*std::get<ObservationEvent>(e[1]).observations[0].noise)(0, 0), 0.25);
}

void expectError(bool g2o, const std::string& text, const std::string& where, const std::string& what) {
  try {
    auto s = g2o ? openG2oText("f", text) : openIsamText("f", text);
    drain(*s);
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(GraphFile, MalformedRecordsNameFileAndLine) {
  const std::string odo = "ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01\n";
  expectError(false, odo + "ODOMETRY 1 2 1 0 0 0.01 0 0\n", "f:2", "expected 12 fields");
  expectError(false, odo + "ODOMETRY 1 2 nan 0 0 0.01 0 0 0.01 0 0.01\n", "f:2", "non-finite");
  expectError(false, odo + "ODOMETRY 1 2 x 0 0 0.01 0 0 0.01 0 0.01\n", "f:2", "bad number 'x'");
  expectError(false, odo + "POINT 1 2\n", "f:2", "unknown record tag 'POINT'");
  expectError(false, odo + "LANDMARK 1 0 1 1 0.4 0 0.4\n", "f:2", "both as a pose and as a landmark");
  expectError(false, odo + "LANDMARK 1 5 1 1 0.4 0 0.4\nODOMETRY 1 5 1 0 0 0.01 0 0 0.01 0 0.01\n", "f:3",
              "both as a pose and as a landmark");
  expectError(false, odo + "ODOMETRY 0 2 1 0 0 0.01 0 0 0.01 0 0.01\n", "f:2", "time order");  // time going back
  expectError(false, odo + "LANDMARK 0 9 1 1 0.4 0 0.4\n", "f:2", "time order");
  expectError(false, odo + "ODOMETRY 1 0 1 0 0 0.01 0 0 0.01 0 0.01\n", "f:2", "reached twice");
  expectError(false, "ODOMETRY 0 1 1 0 0 0.01 0 0 -0.01 0 0.01\n", "f:1", "not positive definite");
  expectError(false, odo + "LANDMARK 1 9 1 1 0.4 0 0.4\nBR 1 9 0.1 2 0.1 0.1\n", "f:3", "one kind of landmark observation");
  expectError(false, "BR 0 9 0.1 -2 0.1 0.1\n", "f:1", "range");
  expectError(false, "ODOMETRY -1 1 1 0 0 0.01 0 0 0.01 0 0.01\n", "f:1", "bad id");
  expectError(true, "EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n", "f:1", "expected 12 fields");
  expectError(true, "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n", "f:1", "EDGE_SE2_XY");  // lists the supported tags
  expectError(true, "VERTEX_XY 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "f:2", "both as a pose and as a landmark");
  // A second estimate of one vertex would be ignored or replace the first.
  expectError(true, "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 0 5 5 1\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "f:2", "listed twice");
  expectError(true, "VERTEX_SE2 0 0 0 0\nVERTEX_SE2\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "f:2", "expected 5 fields");
  // A covariance whose information is not finite (1 / 1e-310), and the other way round.
  expectError(false, "ODOMETRY 0 1 1 0 0 1e-310 0 0 1e-310 0 1e-310\n", "f:1", "too close to singular");
  expectError(true, "EDGE_SE2 0 1 1 0 0 1e-310 0 0 1e-310 0 1e-310\n", "f:1", "too close to singular");
  // Angles beyond a turn are not angles.
  expectError(false, "ODOMETRY 0 1 1 0 1e300 0.01 0 0 0.01 0 0.01\n", "f:1", "more than a turn");
  expectError(false, "BR 0 9 7 2 0.1 0.1\n", "f:1", "more than a turn");
  expectError(false, "BR 0 9 1e1 2 0.1 0.1\n", "f:1", "more than a turn");
  expectError(false, "BR 0 9 0.1 2e6 0.1 0.1\n", "f:1", "beyond 10^6 m");  // not "10 to the printed precision"
  // Positions and displacements beyond 10^6 m are corrupt: their landmark's covariance
  // would overflow (1e200 squared) into a NaN map.
  expectError(false, odo + "LANDMARK 1 9 1e200 1 0.4 0 0.4\n", "f:2", "column 4 (x) is beyond 10^6 m");
  expectError(false, odo + "LANDMARK 1 9 1 -2e6 0.4 0 0.4\n", "f:2", "column 5 (y) is beyond 10^6 m");
  expectError(false, "ODOMETRY 0 1 1e7 0 0 0.01 0 0 0.01 0 0.01\n", "f:1", "column 4 (dx) is beyond 10^6 m");
  expectError(true, "VERTEX_SE2 0 1e300 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "f:1", "beyond 10^6 m");
  expectError(true, "VERTEX_SE2 0 0 0 100\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "f:1", "more than a turn");
  expectError(true, "VERTEX_XY 7 0 3e6\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "f:1", "beyond 10^6 m");
}

TEST(GraphFile, NumbersWithAnExplicitSignAreRead) {
  // printf's "%+f" writes "+0.5"; one sign only ("+-1" and "++1" are not numbers).
  auto s = openIsamText("f", "ODOMETRY 0 1 +1.0 -0.5 +0.1 0.01 0 0 0.02 0 0.03\nLANDMARK 1 50 +3 +.5 0.4 0 0.4\n");
  const std::vector<Event> e = drain(*s);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(std::get<OdometryIncrement>(std::get<ControlEvent>(e[0]).input).delta, Vec3(1.0, -0.5, 0.1));
  EXPECT_EQ(std::get<ObservationEvent>(e[1]).observations[0].z, Vec2(3.0, 0.5));
  expectError(false, "ODOMETRY 0 1 +-1 0 0 0.01 0 0 0.01 0 0.01\n", "f:1", "bad number '+-1'");
  expectError(false, "ODOMETRY 0 1 ++1 0 0 0.01 0 0 0.01 0 0.01\n", "f:1", "bad number '++1'");
}

TEST(GraphFile, ConvertRefusesWhatItCannotWriteFinitelyOrAtAll) {
  const fs::path dir = fs::temp_directory_path() / "seif-convert-refusals";
  fs::create_directories(dir);
  // Each increment is finite; their sum, the g2o vertex, is not.
  std::ofstream(dir / "far.txt") << "ODOMETRY 0 1 1e308 0 0 0.01 0 0 0.01 0 0.01\n"
                                    "ODOMETRY 1 2 1e308 0 0 0.01 0 0 0.01 0 0.01\n";
  EXPECT_THROW(convertDataset(dir / "far.txt", DatasetFormat::Isam, dir / "far.g2o", GraphFormat::G2o), DataError);
  EXPECT_FALSE(fs::exists(dir / "far.g2o"));
  std::ofstream(dir / "vertices.g2o") << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_XY 5 2 2\n";
  EXPECT_THROW(convertDataset(dir / "vertices.g2o", DatasetFormat::Auto, dir / "v.txt", GraphFormat::Isam), DataError);
  EXPECT_FALSE(fs::exists(dir / "v.txt"));
  fs::remove_all(dir);
}

TEST(GraphFile, AByteOrderMarkIsNotData) {
  const std::string text = "ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01\nODOMETRY 1 2 1 0 0 0.01 0 0 0.01 0 0.01\n";
  const std::string marked_text = "\xEF\xBB\xBF" + text;  // the sources read the text in place
  auto plain = openIsamText("f", text);
  auto marked = openIsamText("f", marked_text);
  EXPECT_EQ(drain(*plain).size(), drain(*marked).size());
}

TEST(GraphFile, TheRealFileRoundTripsThroughG2oAndRunsTheSameFromBoth) {
  if (!fs::exists(kReal)) GTEST_SKIP() << "victoria_park.txt not found at " << kReal.string() << " (../shared/data)";
  const fs::path dir = fs::temp_directory_path() / "seif-graph-test";
  fs::create_directories(dir);
  {
    auto s = openIsam(kReal);
    std::size_t odometry = 0, observations = 0;
    std::set<int> landmarks;
    for (const Event& e : drain(*s)) {
      if (std::holds_alternative<ControlEvent>(e)) ++odometry;
      if (const auto* o = std::get_if<ObservationEvent>(&e)) {
        observations += o->observations.size();
        for (const Observation& z : o->observations) landmarks.insert(z.landmark);
      }
    }
    EXPECT_EQ(odometry, 6968u);  // one chain over 6969 poses
    EXPECT_EQ(observations, 3640u);
    EXPECT_EQ(landmarks.size(), 151u);
  }
  convertDataset(kReal, DatasetFormat::Auto, dir / "vp.g2o", GraphFormat::G2o);
  convertDataset(dir / "vp.g2o", DatasetFormat::Auto, dir / "vp.txt", GraphFormat::Isam);
  std::ifstream a(kReal), b(dir / "vp.txt");
  std::string la, lb;
  std::size_t lines = 0;
  while (std::getline(a, la)) {
    ASSERT_TRUE(std::getline(b, lb)) << "line " << lines + 1;
    std::istringstream sa(la), sb(lb);
    std::string ta, tb;
    sa >> ta;
    sb >> tb;
    ASSERT_EQ(ta, tb) << "line " << lines + 1;
    double x = 0, y = 0;
    while (sa >> x) {
      ASSERT_TRUE(sb >> y);
      ASSERT_EQ(x, y) << "line " << lines + 1 << ": every number comes back exactly";
    }
    ++lines;
  }
  EXPECT_FALSE(std::getline(b, lb));
  EXPECT_EQ(lines, 10608u);
  // The g2o file gives the same run as the iSAM file.
  for (const char* name : {"ekf", "seif"}) {
    auto isam = openIsam(kReal);
    auto g2o = openG2o(dir / "vp.g2o");
    FilterConfig config;
    config.motion = isam->info().motion;
    config.sensor = isam->info().sensor;
    auto fa = makeFilter(name, isam->info().start_pose, config);
    auto fb = makeFilter(name, g2o->info().start_pose, config);
    const RunOutput ra = runFilter(*fa, *isam), rb = runFilter(*fb, *g2o);
    ASSERT_EQ(ra.trajectory.size(), 6969u);
    ASSERT_EQ(rb.trajectory.size(), 6969u);
    EXPECT_EQ(ra.trajectory.back().pose, rb.trajectory.back().pose) << name;
    EXPECT_EQ(fa->landmarkIds().size(), 151u);
  }
  fs::remove_all(dir);
}

TEST(GraphFile, FuzzInputsAreReadOrRefusedCleanly) {
  std::size_t inputs = 0;
  for (const char* target : {"fuzz_isam", "fuzz_g2o"}) {
    for (const char* kind : {"regressions", "corpus"}) {
      for (const auto& entry : fs::directory_iterator(fs::path(SEIF_SOURCE_DIR) / "fuzz" / kind / target)) {
        std::ifstream in(entry.path(), std::ios::binary);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        try {
          auto s = std::string(target) == "fuzz_isam" ? openIsamText("fuzz", text) : openG2oText("fuzz", text);
          Event e;
          double previous = -INFINITY;
          while (s->next(e)) {
            ASSERT_EQ(fuzz::brokenEvent(e, previous), "") << entry.path();
            previous = eventTime(e);
          }
        } catch (const DataError& e) {
          EXPECT_TRUE(fuzz::printable(e.what())) << entry.path();
        }
        ++inputs;
      }
    }
  }
  EXPECT_GE(inputs, 8u);
}

}  // namespace
