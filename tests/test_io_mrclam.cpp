// Reader and writer of the MRCLAM layout: bit-exact round trip, the real dataset 6, and
// one corrupted line at a time (each must name its file and line).
#include <seif/core/errors.hpp>
#include <seif/io/mrclam.hpp>

#include "../fuzz/fuzz_support.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace fs = std::filesystem;
using namespace seif;
using namespace std::string_literals;

namespace {

const fs::path kRealDir = fs::path(SEIF_SHARED_DATA_DIR) / "mrclam" / "MRCLAM_Dataset6";

#define SKIP_WITHOUT_REAL_DATA()                                                           \
  do {                                                                                     \
    if (!fs::exists(kRealDir / "Barcodes.dat")) {                                          \
      GTEST_SKIP() << "real MRCLAM dataset 6 not found at " << kRealDir.string()           \
                   << " (../shared/data is absent in a fresh clone)";                      \
    }                                                                                      \
  } while (0)

/// A fresh, empty scratch folder per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device rd;
    path_ = fs::temp_directory_path() /
            ("seif_io_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
             std::to_string(rd()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

/// Every field equal, doubles bit for bit (source and dropped are compared by the caller).
void expectSameLog(const RobotLog& a, const RobotLog& b) {
  EXPECT_EQ(a.robot, b.robot);
  ASSERT_EQ(a.odometry.size(), b.odometry.size());
  for (std::size_t i = 0; i < a.odometry.size(); ++i) {
    EXPECT_EQ(bits(a.odometry[i].time), bits(b.odometry[i].time)) << "odometry " << i;
    EXPECT_EQ(bits(a.odometry[i].v), bits(b.odometry[i].v)) << "odometry " << i;
    EXPECT_EQ(bits(a.odometry[i].w), bits(b.odometry[i].w)) << "odometry " << i;
  }
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  for (std::size_t i = 0; i < a.measurements.size(); ++i) {
    EXPECT_EQ(bits(a.measurements[i].time), bits(b.measurements[i].time)) << "measurement " << i;
    EXPECT_EQ(a.measurements[i].subject, b.measurements[i].subject) << "measurement " << i;
    EXPECT_EQ(bits(a.measurements[i].range), bits(b.measurements[i].range)) << "measurement " << i;
    EXPECT_EQ(bits(a.measurements[i].bearing), bits(b.measurements[i].bearing)) << "measurement " << i;
  }
  ASSERT_EQ(a.groundtruth.size(), b.groundtruth.size());
  for (std::size_t i = 0; i < a.groundtruth.size(); ++i) {
    EXPECT_EQ(bits(a.groundtruth[i].time), bits(b.groundtruth[i].time)) << "groundtruth " << i;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(bits(a.groundtruth[i].pose[k]), bits(b.groundtruth[i].pose[k])) << "groundtruth " << i;
    }
  }
  ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
  for (auto ia = a.landmarks.begin(), ib = b.landmarks.begin(); ia != a.landmarks.end(); ++ia, ++ib) {
    EXPECT_EQ(ia->first, ib->first);
    EXPECT_EQ(bits(ia->second.x()), bits(ib->second.x())) << "landmark " << ia->first;
    EXPECT_EQ(bits(ia->second.y()), bits(ib->second.y())) << "landmark " << ia->first;
  }
  ASSERT_EQ(a.noise.has_value(), b.noise.has_value());
  if (a.noise) {
    EXPECT_EQ(bits(a.noise->sigma_v), bits(b.noise->sigma_v));
    EXPECT_EQ(bits(a.noise->sigma_w), bits(b.noise->sigma_w));
    EXPECT_EQ(bits(a.noise->sigma_range), bits(b.noise->sigma_range));
    EXPECT_EQ(bits(a.noise->sigma_bearing), bits(b.noise->sigma_bearing));
  }
}

/// A small log with awkward doubles: 0.1, 1/3, -0.0, subnormals, large epoch stamps.
RobotLog syntheticLog() {
  RobotLog log;
  log.robot = 2;
  const double t0 = 1248444187.156;
  const double odd[] = {0.1, 1.0 / 3.0, -0.0, 5e-324, std::nextafter(1.0, 2.0), -2.0 / 7.0,
                        1e-300, std::numbers::pi};
  for (int i = 0; i < 40; ++i) {
    log.odometry.push_back({t0 + 0.0137 * i, odd[i % 8], odd[(i + 3) % 8]});
  }
  log.odometry.push_back({log.odometry.back().time, 0.25, -0.5});  // equal stamp is allowed
  // Several landmarks share a stamp.
  log.measurements = {{t0 + 0.05, 6, 3.787, -0.257},   {t0 + 0.05, 12, 6.758, -0.005},
                      {t0 + 0.2, 7, 1.0 / 3.0, -0.0},  {t0 + 0.3, 12, 1e-3, std::numbers::pi},
                      {t0 + 0.3, 6, 2.0, -0.1},        {t0 + 0.3, 7, 4.0, 0.2}};
  for (int i = 0; i < 30; ++i) {
    log.groundtruth.push_back({t0 - 1.0 + 0.031 * i, Pose2(0.1 * i, -1.0 / (i + 1), -std::numbers::pi + 0.2 * i)});
  }
  log.landmarks = {{6, Vec2(0.58831396, -4.28264845)}, {7, Vec2(1.0 / 3.0, -0.0)}, {12, Vec2(1e-310, 2.5)}};
  log.noise = NoiseModel{0.1, 1.0 / 3.0, 0.0447, 0.0548};
  return log;
}

void replaceLine(const fs::path& file, long line_no, const std::string& text) {
  std::ifstream in(file, std::ios::binary);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_GE(static_cast<long>(lines.size()), line_no) << file;
  lines[static_cast<std::size_t>(line_no - 1)] = text;
  in.close();
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  for (const auto& l : lines) out << l << '\n';
}

void writeText(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

/// `read` throws a DataError naming `file` and `line`, whose message contains `needle`.
void expectDataError(const std::function<void()>& read, const fs::path& file, long line,
                     const std::string& needle) {
  try {
    read();
    ADD_FAILURE() << "no DataError for " << file.string() << ":" << line;
  } catch (const DataError& e) {
    const std::string what = e.what();
    const std::string prefix = file.string() + (line > 0 ? ":" + std::to_string(line) : "") + ": ";
    EXPECT_EQ(what.rfind(prefix, 0), 0u) << "message: " << what << "\nexpected prefix: " << prefix;
    EXPECT_EQ(e.file(), file.string());
    EXPECT_EQ(e.line(), line);
    EXPECT_NE(what.find(needle), std::string::npos) << "message: " << what << "\nlacks: " << needle;
  }
}

// Line numbers of the synthetic folder written by writeMrclam: 4 header lines, then rows.
constexpr long kFirstDataLine = 5;

}  // namespace

// --- round trip ----------------------------------------------------------------------------

TEST(MrclamRoundTrip, WriteThenReadIsBitExact) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "nested" / "folder";  // created by the writer
  const RobotLog log = syntheticLog();
  writeMrclam(dir, log);
  for (const char* f : {"Barcodes.dat", "Landmark_Groundtruth.dat", "Robot2_Odometry.dat",
                        "Robot2_Measurement.dat", "Robot2_Groundtruth.dat", "meta.json"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  const RobotLog back = readMrclam(dir, 2);
  EXPECT_EQ(back.source, dir.string());
  expectSameLog(log, back);
  EXPECT_EQ(back.dropped.robot_measurements, 0u);
  EXPECT_EQ(back.dropped.unknown_barcodes, 0u);
  EXPECT_EQ(back.dropped.before_first_control, 0u);
}

TEST(MrclamRoundTrip, OptionalFilesAbsentWhenEmpty) {
  TempDir tmp;
  RobotLog log = syntheticLog();
  log.groundtruth.clear();
  log.noise.reset();
  log.landmarks.clear();  // measured subjects still get barcodes
  writeMrclam(tmp.path(), log);
  EXPECT_FALSE(fs::exists(tmp.path() / "Robot2_Groundtruth.dat"));
  EXPECT_FALSE(fs::exists(tmp.path() / "meta.json"));
  const RobotLog back = readMrclam(tmp.path(), 2);
  expectSameLog(log, back);
  EXPECT_TRUE(back.groundtruth.empty());
  EXPECT_FALSE(back.noise.has_value());
}

TEST(MrclamRoundTrip, BarcodesDifferFromSubjects) {
  TempDir tmp;
  writeMrclam(tmp.path(), syntheticLog());
  std::ifstream in(tmp.path() / "Barcodes.dat");
  int rows = 0;
  std::set<int> subjects;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    int subject = 0, barcode = 0;
    fields >> subject >> barcode;
    EXPECT_NE(subject, barcode);
    subjects.insert(subject);
    ++rows;
  }
  EXPECT_EQ(rows, 8);  // robots 1-5 and landmarks 6, 7, 12
  EXPECT_EQ(subjects, (std::set<int>{1, 2, 3, 4, 5, 6, 7, 12}));
}

TEST(MrclamRoundTrip, RealRobot1) {
  SKIP_WITHOUT_REAL_DATA();
  TempDir tmp;
  const RobotLog log = readMrclam(kRealDir, 1);
  writeMrclam(tmp.path(), log);
  expectSameLog(log, readMrclam(tmp.path(), 1));
}

TEST(MrclamWrite, RejectsLogsThatCouldNotBeReadBack) {
  TempDir tmp;
  RobotLog log = syntheticLog();
  log.robot = 6;
  expectDataError([&] { writeMrclam(tmp.path(), log); }, tmp.path(), 0, "outside 1..5");
  log = syntheticLog();
  log.measurements[1].subject = 3;  // a robot
  expectDataError([&] { writeMrclam(tmp.path(), log); }, tmp.path() / "Barcodes.dat", 0, "robots");
  log = syntheticLog();
  log.odometry[2].v = std::numeric_limits<double>::quiet_NaN();
  expectDataError([&] { writeMrclam(tmp.path(), log); }, tmp.path() / "Robot2_Odometry.dat",
                  kFirstDataLine + 2, "non-finite");
  log = syntheticLog();
  log.measurements[3].range = 0.0;
  expectDataError([&] { writeMrclam(tmp.path(), log); }, tmp.path() / "Robot2_Measurement.dat",
                  kFirstDataLine + 3, "range");
  EXPECT_TRUE(fs::is_empty(tmp.path())) << "nothing is written when the log is rejected";
}

TEST(MrclamWrite, RejectsSigmasTheReaderWouldReject) {
  TempDir tmp;
  RobotLog log = syntheticLog();
  log.noise->sigma_w = 0.0;
  expectDataError([&] { writeMrclam(tmp.path(), log); }, tmp.path() / "meta.json", 0,
                  "\"noise.sigma_w\" must be finite and > 0, found 0");
  log.noise->sigma_w = std::numeric_limits<double>::infinity();
  expectDataError([&] { writeMrclam(tmp.path(), log); }, tmp.path() / "meta.json", 0,
                  "\"noise.sigma_w\" must be finite and > 0, found inf");
  EXPECT_TRUE(fs::is_empty(tmp.path())) << "nothing is written when the log is rejected";
}

TEST(MrclamWrite, ReplacesFilesAtomically) {
  // Each file is written under a temporary name and renamed into place: the old file is
  // never rewritten in place (a hard link to it keeps the old text) and no temporary remains.
  TempDir tmp;
  writeMrclam(tmp.path(), syntheticLog());
  const fs::path old_odometry = tmp.path() / "old_odometry";
  fs::create_hard_link(tmp.path() / "Robot2_Odometry.dat", old_odometry);
  const auto before = fs::file_size(old_odometry);
  RobotLog log = syntheticLog();
  log.odometry.resize(3);
  writeMrclam(tmp.path(), log);
  EXPECT_EQ(fs::file_size(old_odometry), before);
  EXPECT_EQ(readMrclam(tmp.path(), 2).odometry.size(), 3u);
  for (const auto& entry : fs::directory_iterator(tmp.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

// --- the real dataset 6 ------------------------------------------------------------------

namespace {
struct RealCounts {
  int robot;
  std::size_t odometry, kept, robot_drops, unknown_drops;
};
// Measured from the files (awk over RobotN_Measurement.dat and Barcodes.dat); odometry and
// kept agree with ../shared/data/README.md. The README's "43 for robot 1, 34 for robot 3,
// 50 for robot 4" are the unknown *barcode values*; they occur 1, 2 and 3 times.
constexpr RealCounts kReal[] = {{1, 61785, 1534, 407, 1},
                                {2, 65005, 3239, 792, 0},
                                {3, 61158, 4348, 1277, 2},
                                {4, 52916, 2023, 373, 3},
                                {5, 60567, 4239, 1139, 0}};
}  // namespace

TEST(MrclamRealData, CountsOfAllFiveRobots) {
  SKIP_WITHOUT_REAL_DATA();
  for (const RealCounts& c : kReal) {
    SCOPED_TRACE("robot " + std::to_string(c.robot));
    const RobotLog log = readMrclam(kRealDir, c.robot);
    EXPECT_EQ(log.robot, c.robot);
    EXPECT_EQ(log.odometry.size(), c.odometry);
    EXPECT_EQ(log.measurements.size(), c.kept);
    EXPECT_EQ(log.dropped.robot_measurements, c.robot_drops);
    EXPECT_EQ(log.dropped.unknown_barcodes, c.unknown_drops);
    EXPECT_EQ(log.dropped.unknown_barcodes > 0, c.robot == 1 || c.robot == 3 || c.robot == 4);
    EXPECT_EQ(log.dropped.before_first_control, 0u);
    EXPECT_EQ(log.landmarks.size(), 15u);
    EXPECT_FALSE(log.groundtruth.empty());
    EXPECT_FALSE(log.noise.has_value());
    std::set<int> seen;
    for (const auto& m : log.measurements) {
      EXPECT_TRUE(log.landmarks.count(m.subject)) << m.subject;
      seen.insert(m.subject);
    }
    EXPECT_EQ(seen.size(), 15u) << "every robot sees all 15 landmarks";
    for (std::size_t i = 1; i < log.odometry.size(); ++i) {
      ASSERT_LE(log.odometry[i - 1].time, log.odometry[i].time);
    }
  }
}

TEST(MrclamRealData, BarcodesAreMappedToSubjects) {
  SKIP_WITHOUT_REAL_DATA();
  const RobotLog log = readMrclam(kRealDir, 1);
  // Robot1_Measurement.dat starts "1248444189.599 14 3.787 -0.257" (barcode 14 = robot 2,
  // dropped), then "1248444189.599 90 6.758 -0.005" (barcode 90 = landmark 15).
  ASSERT_FALSE(log.measurements.empty());
  EXPECT_EQ(log.measurements[0].subject, 15);
  EXPECT_EQ(log.measurements[0].time, 1248444189.599);
  EXPECT_EQ(log.measurements[0].range, 6.758);
  EXPECT_EQ(log.measurements[0].bearing, -0.005);
  // Landmark 6: 0.58831396 -4.28264845.
  EXPECT_EQ(log.landmarks.at(6), Vec2(0.58831396, -4.28264845));
  EXPECT_EQ(log.odometry[0].time, 1248444187.156);
  EXPECT_EQ(log.odometry[0].w, -0.398);
  EXPECT_EQ(log.groundtruth[0].pose, Pose2(1.41277290, -3.89107760, 2.26960000));
}

TEST(MrclamRealData, ReadsQuickly) {
  SKIP_WITHOUT_REAL_DATA();
  const auto start = std::chrono::steady_clock::now();
  std::size_t rows = 0;
  for (int r = 1; r <= 5; ++r) rows += readMrclam(kRealDir, r).odometry.size();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("seconds_for_five_robots", std::to_string(seconds));
  std::cout << "[          ] read 5 robots (" << rows << " odometry rows, ~600k lines) in "
            << seconds << " s\n";
  EXPECT_LT(seconds, 5.0) << "each ~62k-line file should take well under a second";
}

// --- corrupted input: one damaged line at a time ------------------------------------------

class MrclamCorrupt : public ::testing::Test {
 protected:
  void SetUp() override { writeMrclam(dir(), syntheticLog()); }
  const fs::path& dir() const { return tmp_.path(); }
  fs::path file(const char* name) const { return dir() / name; }
  void expectError(const char* name, long line, const std::string& needle) const {
    expectDataError([&] { readMrclam(dir(), 2); }, file(name), line, needle);
  }
  TempDir tmp_;
};

TEST_F(MrclamCorrupt, TruncatedLine) {
  replaceLine(file("Robot2_Odometry.dat"), kFirstDataLine + 7, "1248444187.2519\t0.1");
  expectError("Robot2_Odometry.dat", kFirstDataLine + 7, "expected 3 fields (time v w), found 2");
}

TEST_F(MrclamCorrupt, ExtraField) {
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 1, "1248444187.206\t112\t6.758\t-0.005\t1");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 1, "found 5");
}

TEST_F(MrclamCorrupt, ABearingOfMoreThanATurn) {
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 2, "1248444187.356\t107\t1.5\t1e300");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 2, "angle '1e300' rad in column 4 (bearing) is more than a turn");
}

TEST_F(MrclamCorrupt, ARangeBeyondAThousandKilometres) {
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 2, "1248444187.356\t107\t1e300\t0.1");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 2, "range 1e+300 m is beyond 10^6 m");
}

TEST_F(MrclamCorrupt, AControlFasterThanAnyVehicle) {
  replaceLine(file("Robot2_Odometry.dat"), kFirstDataLine + 7, "1248444187.2519\t-2e3\t0.1");
  expectError("Robot2_Odometry.dat", kFirstDataLine + 7, "speed -2000 m/s is beyond 10^3 m/s");
  replaceLine(file("Robot2_Odometry.dat"), kFirstDataLine + 7, "1248444187.2519\t0.1\t1e300");
  expectError("Robot2_Odometry.dat", kFirstDataLine + 7, "turn rate 1e+300 rad/s is beyond 10^3 rad/s");
}

TEST_F(MrclamCorrupt, NoBarcode) {
  std::ofstream(file("Barcodes.dat")) << "# Subject #    Barcode #\n";
  expectError("Barcodes.dat", 1, "no barcode listed");
}

TEST_F(MrclamCorrupt, AByteOrderMarkIsNotData) {
  std::ifstream in(file("Robot2_Odometry.dat"), std::ios::binary);
  const std::string odometry((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  writeText(file("Robot2_Odometry.dat"), "\xEF\xBB\xBF" + odometry);
  EXPECT_EQ(readMrclam(dir(), 2).odometry.size(), syntheticLog().odometry.size());
}

TEST_F(MrclamCorrupt, NaN) {
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 2, "1248444187.356\t107\tnan\t0.1");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 2, "non-finite number 'nan' in column 3 (range)");
}

TEST_F(MrclamCorrupt, Infinity) {
  replaceLine(file("Robot2_Groundtruth.dat"), kFirstDataLine + 3, "1248444186.249\t0.3\t-inf\t0.1");
  expectError("Robot2_Groundtruth.dat", kFirstDataLine + 3, "non-finite number '-inf' in column 3 (y)");
}

TEST_F(MrclamCorrupt, LetterInNumber) {
  replaceLine(file("Robot2_Odometry.dat"), kFirstDataLine, "1248444187.156\t1.2x\t0.3");
  expectError("Robot2_Odometry.dat", kFirstDataLine, "bad number '1.2x' in column 2 (v)");
  replaceLine(file("Robot2_Odometry.dat"), kFirstDataLine, "1248444187.156\t0.1\tx1.2");
  expectError("Robot2_Odometry.dat", kFirstDataLine, "bad number 'x1.2' in column 3 (w)");
}

TEST_F(MrclamCorrupt, NonIntegerBarcode) {
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine, "1248444187.206\t106.0\t3.787\t-0.257");
  expectError("Robot2_Measurement.dat", kFirstDataLine, "bad integer '106.0' in column 2 (barcode)");
}

TEST_F(MrclamCorrupt, NumberOutOfRange) {
  replaceLine(file("Landmark_Groundtruth.dat"), kFirstDataLine + 1, "7\t1e999\t0\t0\t0");
  expectError("Landmark_Groundtruth.dat", kFirstDataLine + 1, "out of range in column 2 (x)");
}

// Ground truth far beyond any arena (or a heading of many turns) is corrupt: its errors would
// be reported as infinite, or its landmark dropped from the scores, with a zero exit.
TEST_F(MrclamCorrupt, GroundTruthBeyondTheWorld) {
  replaceLine(file("Landmark_Groundtruth.dat"), kFirstDataLine + 1, "7\t1e300\t0\t0\t0");
  expectError("Landmark_Groundtruth.dat", kFirstDataLine + 1, "1e+300 m in column 2 (x) is beyond 10^6 m");
}

TEST_F(MrclamCorrupt, GroundTruthPoseBeyondTheWorldOrATurn) {
  replaceLine(file("Robot2_Groundtruth.dat"), kFirstDataLine + 3, "1248444186.249\t0.3\t-2e6\t0.1");
  expectError("Robot2_Groundtruth.dat", kFirstDataLine + 3, "-2e+06 m in column 3 (y) is beyond 10^6 m");
  replaceLine(file("Robot2_Groundtruth.dat"), kFirstDataLine + 3, "1248444186.249\t0.3\t0.2\t1e5");
  expectError("Robot2_Groundtruth.dat", kFirstDataLine + 3, "more than a turn");
}

TEST_F(MrclamCorrupt, TimeGoesBack) {
  // Odometry rows are 0.0137 s apart; row 10 gets a stamp before row 9.
  replaceLine(file("Robot2_Odometry.dat"), kFirstDataLine + 10, "1248444187.2\t0.1\t0.2");
  expectError("Robot2_Odometry.dat", kFirstDataLine + 10, "goes backwards");
  writeMrclam(dir(), syntheticLog());
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 5, "1248444187.1\t107\t4\t0.2");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 5, "goes backwards");
}

TEST_F(MrclamCorrupt, RangeNotPositive) {
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 4, "1248444187.456\t106\t0\t-0.1");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 4, "range 0 must be positive");
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 4, "1248444187.456\t106\t-2\t-0.1");
  expectError("Robot2_Measurement.dat", kFirstDataLine + 4, "range -2 must be positive");
}

TEST_F(MrclamCorrupt, BarcodeListedTwice) {
  replaceLine(file("Barcodes.dat"), kFirstDataLine + 6, "7\t106");  // line 10, first on line 10-4
  expectError("Barcodes.dat", kFirstDataLine + 6, "barcode 106 listed twice (first on line 10)");
}

TEST_F(MrclamCorrupt, LandmarkThatIsARobot) {
  replaceLine(file("Landmark_Groundtruth.dat"), kFirstDataLine, "3\t0.5\t0.5\t0\t0");
  expectError("Landmark_Groundtruth.dat", kFirstDataLine, "is a robot");
}

TEST_F(MrclamCorrupt, MissingRequiredFile) {
  for (const char* name : {"Barcodes.dat", "Landmark_Groundtruth.dat", "Robot2_Odometry.dat",
                           "Robot2_Measurement.dat"}) {
    SCOPED_TRACE(name);
    writeMrclam(dir(), syntheticLog());
    fs::remove(file(name));
    expectError(name, 0, "missing required file");
  }
}

TEST_F(MrclamCorrupt, OptionalFilesMayBeMissing) {
  fs::remove(file("Robot2_Groundtruth.dat"));
  fs::remove(file("meta.json"));
  const RobotLog log = readMrclam(dir(), 2);
  EXPECT_TRUE(log.groundtruth.empty());
  EXPECT_FALSE(log.noise.has_value());
  EXPECT_EQ(log.odometry.size(), syntheticLog().odometry.size());
}

TEST_F(MrclamCorrupt, UnknownRobotNumber) {
  // The argument: no file to name a line of, so the error names the folder.
  for (const int robot : {0, 6, -1}) {
    expectDataError([&] { readMrclam(dir(), robot); }, dir(), 0, "outside 1..5");
  }
  // A robot folder that does not exist is a missing file.
  expectDataError([&] { readMrclam(dir(), 4); }, dir() / "Robot4_Odometry.dat", 0, "missing required file");
  // meta.json naming a robot outside 1..5.
  writeText(file("meta.json"), R"({"format": "seif-mrclam", "robot": 9})");
  expectError("meta.json", 0, "\"robot\" must be an integer in 1..5");
}

TEST_F(MrclamCorrupt, MalformedMetaJson) {
  writeText(file("meta.json"), "{\"noise\": {\"sigma_v\": 0.1,");
  expectError("meta.json", 0, "malformed JSON");
  writeText(file("meta.json"), R"({"noise": {"sigma_v": 0.1, "sigma_w": 0.1, "sigma_range": 0.1}})");
  expectError("meta.json", 0, "lacks \"sigma_bearing\"");
  writeText(file("meta.json"), R"({"noise": {"sigma_v": -0.1, "sigma_w": 0.1, "sigma_range": 0.1, "sigma_bearing": 1}})");
  expectError("meta.json", 0, "sigma_v");
  writeText(file("meta.json"), R"({"format": "other", "noise": {}})");
  expectError("meta.json", 0, "format");
  writeText(file("meta.json"), R"([1, 2])");
  expectError("meta.json", 0, "object");
  // Every key is optional: an empty object means "no noise given".
  writeText(file("meta.json"), "{}");
  EXPECT_FALSE(readMrclam(dir(), 2).noise.has_value());
}

TEST_F(MrclamCorrupt, MetaJsonNumberOverflow) {
  // nlohmann throws out_of_range (406) here, not parse_error: still a DataError naming the file.
  writeText(file("meta.json"),
            R"({"noise": {"sigma_v": 1e400, "sigma_w": 0.1, "sigma_range": 0.1, "sigma_bearing": 0.1}})");
  expectError("meta.json", 0, "number overflow parsing '1e400'");
  writeText(file("meta.json"), R"({"x": 1e400})");
  expectError("meta.json", 0, "1e400");
}

TEST_F(MrclamCorrupt, MetaJsonSigmasMustBePositive) {
  writeText(file("meta.json"),
            R"({"noise": {"sigma_v": 0.1, "sigma_w": 0.1, "sigma_range": 0, "sigma_bearing": 0.1}})");
  expectError("meta.json", 0, "\"noise.sigma_range\" must be finite and > 0, found 0");
  writeText(file("meta.json"),
            R"({"noise": {"sigma_v": 0.1, "sigma_w": -0.0, "sigma_range": 1, "sigma_bearing": 0.1}})");
  expectError("meta.json", 0, "\"noise.sigma_w\" must be finite and > 0, found -0");
  writeText(file("meta.json"),
            R"({"noise": {"sigma_v": 0.1, "sigma_w": 0.1, "sigma_range": 1, "sigma_bearing": 1e-300}})");
  EXPECT_EQ(readMrclam(dir(), 2).noise->sigma_bearing, 1e-300);
}

TEST_F(MrclamCorrupt, MetaJsonDeeplyNested) {
  // A message used to dump() the offending value, recursing once per level: a stack overflow.
  const std::size_t depth = 200000;
  writeText(file("meta.json"), "{\"robot\": " + std::string(depth, '[') + std::string(depth, ']') + "}");
  expectError("meta.json", 0, "\"robot\" must be an integer in 1..5, found an array");
}

TEST_F(MrclamCorrupt, SymbolicLinkLoop) {
  for (const char* name : {"Robot2_Odometry.dat", "meta.json", "Robot2_Groundtruth.dat"}) {
    SCOPED_TRACE(name);
    writeMrclam(dir(), syntheticLog());
    fs::remove(file(name));
    fs::create_symlink(name, file(name));  // points at itself
    expectError(name, 0, "symbolic-link loop");
    fs::remove(file(name));
  }
}

TEST_F(MrclamCorrupt, NonPrintableBytesAreEscaped) {
  // what() is a C string: a raw NUL would cut the message after "'3.7".
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine,
              "1248444187.206\t106\t3.7\0abc\x1b[2J\t-0.257"s);
  expectError("Robot2_Measurement.dat", kFirstDataLine,
              "bad number '3.7\\x00abc\\x1b[2J' in column 3 (range)");
}

TEST(DataErrorMessage, EscapesWhatIsNotPrintableUtf8) {
  // Kept: valid UTF-8 (é € 😀). Escaped: controls, DEL, a stray byte, a truncated sequence,
  // a C1 control (U+0085), a UTF-16 surrogate.
  const DataError e("a\nb.dat", 3, "x\0y\x7f\té€😀 \xff\xc3 \xc2\x85 \xed\xa0\x80"s);
  EXPECT_EQ(std::string(e.what()),
            "a\\x0ab.dat:3: x\\x00y\\x7f\\x09é€😀 \\xff\\xc3 \\xc2\\x85 \\xed\\xa0\\x80");
  EXPECT_EQ(e.file(), "a\nb.dat");  // the name as given
}

// --- in memory ---------------------------------------------------------------------------

namespace {
std::string readText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

MrclamFiles filesOf(const fs::path& dir) {
  MrclamFiles files;
  files.folder = dir.string();
  for (const auto& entry : fs::directory_iterator(dir)) {
    files.text.emplace(entry.path().filename().string(), readText(entry.path()));
  }
  return files;
}

std::string messageOf(const std::function<void()>& read) {
  try {
    read();
  } catch (const DataError& e) {
    return e.what();
  }
  return "no DataError";
}
}  // namespace

TEST_F(MrclamCorrupt, InMemoryReaderMatchesTheFolderReader) {
  const RobotLog from_memory = readMrclam(filesOf(dir()), 2);
  EXPECT_EQ(from_memory.source, dir().string());
  expectSameLog(readMrclam(dir(), 2), from_memory);

  // The same message, file name and line included, for a damaged line and a missing file.
  replaceLine(file("Robot2_Measurement.dat"), kFirstDataLine + 2, "1248444187.356\t107\tnan\t0.1");
  const std::string message = messageOf([&] { readMrclam(dir(), 2); });
  const std::string where = file("Robot2_Measurement.dat").string() + ":7: non-finite number";
  EXPECT_NE(message.find(where), std::string::npos) << message;
  EXPECT_EQ(messageOf([&] { readMrclam(filesOf(dir()), 2); }), message);
  MrclamFiles files = filesOf(dir());
  files.text.erase("Barcodes.dat");
  EXPECT_EQ(messageOf([&] { readMrclam(files, 2); }),
            file("Barcodes.dat").string() + ": missing required file");
  EXPECT_EQ(messageOf([&] { readMrclam(files, 6); }),
            dir().string() + ": robot number 6 is outside 1..5");
}

TEST(MrclamMetaJson, ReadsTextInMemory) {
  const auto noise = readMetaJson(
      R"({"noise": {"sigma_v": 1, "sigma_w": 2, "sigma_range": 3, "sigma_bearing": 4}})", "m");
  ASSERT_TRUE(noise.has_value());
  EXPECT_EQ(noise->sigma_range, 3.0);
  EXPECT_FALSE(readMetaJson(R"({"format": "seif-mrclam", "robot": 2})", "m").has_value());
  expectDataError([] { readMetaJson("{", "some/meta.json"); }, "some/meta.json", 0, "malformed JSON");
  expectDataError([] { readMetaJson(R"({"robot": "1"})", "x.json"); }, "x.json", 0, "found \"1\"");
}

// Every input kept by the fuzzers (fuzz/regressions: crashes found and handcrafted nasty
// inputs; fuzz/corpus: the seeds) is read or rejected with a DataError, nothing else.
TEST(MrclamFuzzInputs, AreReadOrRejectedWithADataError) {
  const fs::path fuzz_dir = fs::path(SEIF_SOURCE_DIR) / "fuzz";
  std::size_t inputs = 0;
  for (const char* kind : {"regressions", "corpus"}) {
    for (const char* target : {"fuzz_mrclam", "fuzz_meta_json"}) {
      const fs::path folder = fuzz_dir / kind / target;
      ASSERT_TRUE(fs::is_directory(folder)) << folder;
      for (const auto& entry : fs::directory_iterator(folder)) {
        SCOPED_TRACE(entry.path().string());
        const std::string input = readText(entry.path());
        ++inputs;
        try {
          if (std::string_view(target) == "fuzz_mrclam") {
            const RobotLog log = readMrclam(fuzz::splitMrclamInput(input), fuzz::kRobot);
            EXPECT_EQ(fuzz::brokenInvariant(log), "");
          } else if (const auto noise = readMetaJson(input, "meta.json")) {
            EXPECT_TRUE(fuzz::isValidNoise(*noise));
          }
        } catch (const DataError& e) {
          EXPECT_TRUE(fuzz::isPrintable(e.what())) << e.what();
        }
      }
    }
  }
  EXPECT_GE(inputs, 20u);
}

TEST_F(MrclamCorrupt, CommentsBlankLinesAndMixedWhitespace) {
  writeText(file("Robot2_Odometry.dat"),
            "# a comment\n"
            "\n"
            "  1.0 \t 0.5\t\t-0.25  \r\n"
            "   # an indented comment\n"
            "\t \n"
            "2.0 0.5 -0.25\n"
            "2.0\t0.75\t0.0");  // equal stamps are fine; no final newline
  const RobotLog log = readMrclam(dir(), 2);
  ASSERT_EQ(log.odometry.size(), 3u);
  EXPECT_EQ(log.odometry[0].time, 1.0);
  EXPECT_EQ(log.odometry[0].w, -0.25);
  EXPECT_EQ(log.odometry[2].v, 0.75);
  // Line numbers count comments and blank lines.
  writeText(file("Robot2_Odometry.dat"), "# c\n\n1.0 0.5 0.1\n# c\n\n0.5 0.5 0.1\n");
  expectError("Robot2_Odometry.dat", 6, "goes backwards");
}

TEST(MrclamCorruptReal, DamagedLinesDeepInRobot1) {
  SKIP_WITHOUT_REAL_DATA();
  TempDir tmp;
  for (const char* f : {"Barcodes.dat", "Landmark_Groundtruth.dat", "Robot1_Odometry.dat",
                        "Robot1_Measurement.dat", "Robot1_Groundtruth.dat"}) {
    fs::copy_file(kRealDir / f, tmp.path() / f);
  }
  const auto read = [&] { readMrclam(tmp.path(), 1); };
  const fs::path odo = tmp.path() / "Robot1_Odometry.dat";
  const fs::path meas = tmp.path() / "Robot1_Measurement.dat";
  const fs::path barcodes = tmp.path() / "Barcodes.dat";

  replaceLine(odo, 30000, "1248444500.000 \t  nan \t -0.398");
  expectDataError(read, odo, 30000, "non-finite number 'nan' in column 2 (v)");
  fs::copy_file(kRealDir / "Robot1_Odometry.dat", odo, fs::copy_options::overwrite_existing);

  replaceLine(odo, 61789, "1248445000.0");  // the last line, truncated
  expectDataError(read, odo, 61789, "expected 3 fields");
  fs::copy_file(kRealDir / "Robot1_Odometry.dat", odo, fs::copy_options::overwrite_existing);

  replaceLine(meas, 1000, "1248444640.O91 \t  90 \t  3.309 \t -0.278");  // letter O for zero
  expectDataError(read, meas, 1000, "bad number '1248444640.O91' in column 1 (time)");
  fs::copy_file(kRealDir / "Robot1_Measurement.dat", meas, fs::copy_options::overwrite_existing);

  replaceLine(meas, 1500, "1248444000.000 \t  90 \t  3.309 \t -0.278");
  expectDataError(read, meas, 1500, "goes backwards");
  fs::copy_file(kRealDir / "Robot1_Measurement.dat", meas, fs::copy_options::overwrite_existing);

  replaceLine(barcodes, 24, " 20 \t  63");  // 63 is landmark 6's barcode (line 10)
  expectDataError(read, barcodes, 24, "barcode 63 listed twice (first on line 10)");
  fs::copy_file(kRealDir / "Barcodes.dat", barcodes, fs::copy_options::overwrite_existing);

  fs::remove(meas);
  expectDataError(read, meas, 0, "missing required file");
  fs::copy_file(kRealDir / "Robot1_Measurement.dat", meas);

  expectDataError([&] { readMrclam(tmp.path(), 7); }, tmp.path(), 0, "robot number 7 is outside 1..5");
  EXPECT_EQ(readMrclam(tmp.path(), 1).measurements.size(), 1534u);  // restored
}
