// Reader and writer of the UTIAS MRCLAM layout (include/seif/io/mrclam.hpp,
// ../shared/data/README.md). Files are read whole and parsed with std::from_chars: the
// 62k-line odometry files of dataset 6 take a few milliseconds.
#include <seif/core/errors.hpp>
#include "core/files.hpp"
#include <seif/io/mrclam.hpp>
#include "io/text_table.hpp"

#include "mrclam_rows.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cassert>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

namespace seif {
namespace {

namespace fs = std::filesystem;

constexpr int kFirstRobot = 1;
constexpr int kLastRobot = 5;
constexpr int kBarcodeOffset = 100;  // writer: barcode = 100 + subject

bool isRobot(int subject) { return subject >= kFirstRobot && subject <= kLastRobot; }

/// File `name` of `folder` as named in messages.
std::string fileName(std::string_view folder, std::string_view name) {
  return (fs::path(folder) / name).string();
}

std::string robotFile(int robot, const char* kind) {
  return "Robot" + std::to_string(robot) + "_" + kind + ".dat";
}

/// A JSON value as shown in a message: a scalar as written (shortened), a container by its
/// kind (dump() recurses once per level: a deeply nested value would overflow the stack).
std::string shown(const nlohmann::json& value) {
  if (value.is_object()) return "an object";
  if (value.is_array()) return "an array";
  constexpr std::size_t kMax = 40;
  const std::string text = value.dump();
  return text.size() > kMax ? text.substr(0, kMax) + "..." : text;
}

/// The one rule for a meta.json sigma, shared by reader and writer.
void checkSigma(const std::string& file, const char* key, double sigma) {
  if (!std::isfinite(sigma) || !(sigma > 0.0)) {
    throw DataError(file, 0, std::string("\"noise.") + key + "\" must be finite and > 0, found " +
                                 formatDouble(sigma));
  }
}

struct SigmaKey {
  const char* key;
  double NoiseModel::*member;
};
constexpr SigmaKey kSigmaKeys[] = {{"sigma_v", &NoiseModel::sigma_v},
                                   {"sigma_w", &NoiseModel::sigma_w},
                                   {"sigma_range", &NoiseModel::sigma_range},
                                   {"sigma_bearing", &NoiseModel::sigma_bearing}};

std::optional<NoiseModel> parseMetaJson(std::string_view text, const std::string& name) {
  const nlohmann::json j = nlohmann::json::parse(text);
  if (!j.is_object()) throw DataError(name, 0, "expected a JSON object");
  if (const auto it = j.find("format"); it != j.end()) {
    if (!it->is_string() || it->get<std::string>() != "seif-mrclam") {
      throw DataError(name, 0, "\"format\" must be \"seif-mrclam\", found " + shown(*it));
    }
  }
  if (const auto it = j.find("robot"); it != j.end()) {
    const bool ok = it->is_number_integer() && it->get<long long>() >= kFirstRobot &&
                      it->get<long long>() <= kLastRobot;
    if (!ok) {
      throw DataError(name, 0, "\"robot\" must be an integer in 1..5, found " + shown(*it));
    }
  }
  const auto it = j.find("noise");
  if (it == j.end()) return std::nullopt;
  if (!it->is_object()) throw DataError(name, 0, "\"noise\" must be an object");
  NoiseModel noise;
  for (const auto& [key, member] : kSigmaKeys) {
    const auto s = it->find(key);
    if (s == it->end()) throw DataError(name, 0, std::string("\"noise\" lacks \"") + key + "\"");
    if (!s->is_number()) {
      throw DataError(name, 0,
                      std::string("\"noise.") + key + "\" must be a number, found " + shown(*s));
    }
    noise.*member = s->get<double>();
    checkSigma(name, key, noise.*member);
  }
  return noise;
}

}  // namespace

Barcodes parseBarcodes(TextTable& t) {
  Barcodes barcodes;
  std::map<int, long> subject_line;
  std::map<int, long> barcode_line;
  while (t.next()) {
    t.expect({"subject", "barcode"});
    const int subject = t.integer(0);
    const int barcode = t.integer(1);
    if (subject < kClutterSubject) t.fail("subject number " + std::to_string(subject) + " must not be negative");
    if (barcode < 0) t.fail("barcode " + std::to_string(barcode) + " must not be negative");
    if (const auto [it, fresh] = barcode_line.emplace(barcode, t.line()); !fresh) {
      t.fail("barcode " + std::to_string(barcode) + " listed twice (first on line " + std::to_string(it->second) + ")");
    }
    if (const auto [it, fresh] = subject_line.emplace(subject, t.line()); !fresh) {
      t.fail("subject " + std::to_string(subject) + " listed twice (first on line " + std::to_string(it->second) + ")");
    }
    barcodes.emplace(barcode, subject);
  }
  if (barcodes.empty()) t.fail("no barcode listed (expected rows of: subject barcode)");
  return barcodes;
}

std::map<int, Vec2> parseLandmarks(TextTable& t) {
  std::map<int, Vec2> landmarks;
  while (t.next()) {
    t.expect({"subject", "x", "y", "x_sd", "y_sd"});
    const int subject = t.integer(0);
    const double x = t.coordinate(1);
    const double y = t.coordinate(2);
    const double x_sd = t.real(3);
    const double y_sd = t.real(4);
    if (subject < 1) t.fail("subject number " + std::to_string(subject) + " must be positive");
    if (isRobot(subject)) t.fail("subject " + std::to_string(subject) + " is a robot (1-5), not a landmark");
    if (x_sd < 0.0 || y_sd < 0.0) t.fail("negative standard deviation");
    if (!landmarks.emplace(subject, Vec2(x, y)).second) t.fail("landmark " + std::to_string(subject) + " listed twice");
  }
  return landmarks;
}

OdometryRecord odometryRow(TextTable& t, TimeOrder& order) {
  t.expect({"time", "v", "w"});
  OdometryRecord r;
  r.time = t.real(0);
  r.v = t.real(1);
  r.w = t.real(2);
  order.check(t, r.time);
  if (std::abs(r.v) > kMaxSpeed) t.fail("speed " + formatDouble(r.v) + " m/s is beyond 10^3 m/s");
  if (std::abs(r.w) > kMaxTurnRate) t.fail("turn rate " + formatDouble(r.w) + " rad/s is beyond 10^3 rad/s");
  return r;
}

std::optional<MeasurementRecord> measurementRow(TextTable& t, TimeOrder& order, const Barcodes& barcodes,
                                                DropCounts& dropped) {
  t.expect({"time", "barcode", "range", "bearing"});
  MeasurementRecord m;
  m.time = t.real(0);
  const int barcode = t.integer(1);
  m.range = t.range(2);
  m.bearing = t.angle(3);
  order.check(t, m.time);
  const auto it = barcodes.find(barcode);
  if (it == barcodes.end()) {
    ++dropped.unknown_barcodes;
    return std::nullopt;
  }
  if (isRobot(it->second)) {
    ++dropped.robot_measurements;
    return std::nullopt;
  }
  m.subject = it->second;
  return m;
}

TimedPose groundtruthRow(TextTable& t, TimeOrder& order) {
  t.expect({"time", "x", "y", "theta"});
  TimedPose p;
  p.time = t.real(0);
  p.pose = Pose2(t.coordinate(1), t.coordinate(2), t.angle(3));
  order.check(t, p.time);
  return p;
}

namespace {

/// The reader proper. `read(name)` returns the text of file `name` of the folder, nullopt
/// when it is absent; the view it returns stays valid until its next call.
template <class Read>
RobotLog parseMrclam(const std::string& folder, int robot, Read&& read) {
  if (!isRobot(robot)) {
    throw DataError(folder, 0, "robot number " + std::to_string(robot) + " is outside 1..5");
  }
  const auto required = [&](const std::string& name) {
    const std::optional<std::string_view> text = read(name);
    if (!text) throw DataError(fileName(folder, name), 0, "missing required file");
    return *text;
  };
  RobotLog log;
  log.source = folder;
  log.robot = robot;
  Barcodes barcodes;

  {
    TextTable t(fileName(folder, "Barcodes.dat"), required("Barcodes.dat"));
    barcodes = parseBarcodes(t);
  }
  {
    TextTable t(fileName(folder, "Landmark_Groundtruth.dat"), required("Landmark_Groundtruth.dat"));
    log.landmarks = parseLandmarks(t);
  }
  {
    const std::string name = robotFile(robot, "Odometry");
    TextTable t(fileName(folder, name), required(name));
    TimeOrder order;
    while (t.next()) log.odometry.push_back(odometryRow(t, order));
  }
  {
    const std::string name = robotFile(robot, "Measurement");
    TextTable t(fileName(folder, name), required(name));
    TimeOrder order;
    while (t.next()) {
      if (const auto m = measurementRow(t, order, barcodes, log.dropped)) log.measurements.push_back(*m);
    }
  }
  const std::string gt_name = robotFile(robot, "Groundtruth");
  if (const std::optional<std::string_view> text = read(gt_name)) {
    TextTable t(fileName(folder, gt_name), *text);
    TimeOrder order;
    while (t.next()) log.groundtruth.push_back(groundtruthRow(t, order));
  }

  // meta.json (optional).
  if (const std::optional<std::string_view> text = read("meta.json")) {
    log.noise = readMetaJson(*text, fileName(folder, "meta.json"));
  }
  return log;
}

// --- writing -----------------------------------------------------------------------------

constexpr const char* kHeaderTitle =
    "# seif: a log in the layout of the UTIAS Multi-Robot Cooperative Localization and "
    "Mapping Dataset\n# written by seif::writeMrclam\n";

class Writer {
 public:
  explicit Writer(std::string header) : text_(std::move(header)) {}
  void field(double x) {
    sep();
    std::array<char, 64> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), x);  // shortest exact
    text_.append(buf.data(), res.ptr);
  }
  void field(int x) {
    sep();
    text_ += std::to_string(x);
  }
  void endLine() {
    text_ += '\n';
    first_ = true;
  }
  void save(const fs::path& path) const { writeFileAtomically(path, text_); }

 private:
  void sep() {
    if (!first_) text_ += '\t';
    first_ = false;
  }
  std::string text_;
  bool first_ = true;
};

constexpr long kHeaderLines = 4;  // two title lines, the format line, the column line

/// Checks, before anything is written, that `log` reads back as itself.
void validateForWriting(const fs::path& dir, const RobotLog& log, const std::set<int>& subjects) {
  if (!isRobot(log.robot)) {
    throw DataError(dir.string(), 0, "robot number " + std::to_string(log.robot) + " is outside 1..5");
  }
  const std::string barcodes = (dir / "Barcodes.dat").string();
  for (const int s : subjects) {
    if (s == kClutterSubject && !log.landmarks.contains(s)) continue;  // clutter (measurements only)
    if (s <= kLastRobot) {
      throw DataError(barcodes, 0, "landmark subject " + std::to_string(s) +
                                       " is not allowed: subjects 1-5 are robots");
    }
    if (s > INT_MAX - kBarcodeOffset) {
      throw DataError(barcodes, 0, "landmark subject " + std::to_string(s) + " is too large");
    }
  }
  const auto finite = [](std::initializer_list<double> xs) {
    for (const double x : xs) {
      if (!std::isfinite(x)) return false;
    }
    return true;
  };
  const std::string lm = (dir / "Landmark_Groundtruth.dat").string();
  long line = kHeaderLines;
  for (const auto& [s, p] : log.landmarks) {
    ++line;
    if (!finite({p.x(), p.y()})) throw DataError(lm, line, "cannot write a non-finite landmark position");
  }
  const auto checkTime = [](const std::string& file, long row_line, double t, double& prev) {
    if (!std::isfinite(t)) throw DataError(file, row_line, "cannot write a non-finite time");
    if (t < prev) throw DataError(file, row_line, "cannot write: time goes backwards");
    prev = t;
  };
  const std::string odo = (dir / robotFile(log.robot, "Odometry")).string();
  double prev = -std::numeric_limits<double>::infinity();
  line = kHeaderLines;
  for (const auto& r : log.odometry) {
    ++line;
    checkTime(odo, line, r.time, prev);
    if (!finite({r.v, r.w})) throw DataError(odo, line, "cannot write a non-finite control");
  }
  const std::string meas = (dir / robotFile(log.robot, "Measurement")).string();
  prev = -std::numeric_limits<double>::infinity();
  line = kHeaderLines;
  for (const auto& m : log.measurements) {
    ++line;
    checkTime(meas, line, m.time, prev);
    if (!finite({m.range, m.bearing})) throw DataError(meas, line, "cannot write a non-finite measurement");
    if (!(m.range > 0.0)) throw DataError(meas, line, "cannot write a range <= 0");
  }
  const std::string gt = (dir / robotFile(log.robot, "Groundtruth")).string();
  prev = -std::numeric_limits<double>::infinity();
  line = kHeaderLines;
  for (const auto& g : log.groundtruth) {
    ++line;
    checkTime(gt, line, g.time, prev);
    if (!g.pose.allFinite()) throw DataError(gt, line, "cannot write a non-finite pose");
  }
  if (log.noise) {
    for (const auto& [key, member] : kSigmaKeys) {
      checkSigma((dir / "meta.json").string(), key, (*log.noise).*member);
    }
  }
}

}  // namespace

std::optional<NoiseModel> readMetaJson(std::string_view text, const std::string& name_for_errors) {
  try {
    return parseMetaJson(text, name_for_errors);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for a number beyond double ("1e400"). The message quotes
    // the token read last, which may be the whole file.
    constexpr std::size_t kMax = 200;
    const std::string what = e.what();
    throw DataError(name_for_errors, 0,
                    "malformed JSON: " + (what.size() > kMax ? what.substr(0, kMax) + "..." : what));
  }
}

RobotLog readMrclam(const MrclamFiles& files, int robot) {
  return parseMrclam(files.folder, robot, [&](const std::string& name) -> std::optional<std::string_view> {
    const auto it = files.text.find(name);
    if (it == files.text.end()) return std::nullopt;
    return std::string_view(it->second);
  });
}

RobotLog readMrclam(const std::filesystem::path& dir, int robot) {
  std::optional<std::string> text;  // the file being parsed; one at a time
  return parseMrclam(dir.string(), robot, [&](const std::string& name) -> std::optional<std::string_view> {
    text = readFileIfExists(dir / name);
    if (!text) return std::nullopt;
    return std::string_view(*text);
  });
}

void writeMrclam(const std::filesystem::path& dir, const RobotLog& log) {
  std::set<int> subjects;
  for (const auto& [s, p] : log.landmarks) subjects.insert(s);
  for (const auto& m : log.measurements) subjects.insert(m.subject);
  validateForWriting(dir, log, subjects);

  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw DataError(dir.string(), 0, "cannot create folder: " + ec.message());

  {
    Writer w(std::string(kHeaderTitle) + "# Barcode Data Format:\n# Subject #    Barcode #\n");
    for (int r = kFirstRobot; r <= kLastRobot; ++r) {
      w.field(r);
      w.field(kBarcodeOffset + r);
      w.endLine();
    }
    for (const int s : subjects) {
      w.field(s);
      w.field(kBarcodeOffset + s);
      w.endLine();
    }
    w.save(dir / "Barcodes.dat");
  }
  {
    Writer w(std::string(kHeaderTitle) +
             "# Landmark Groundtruth Data Format:\n"
             "# Subject #    x [m]    y [m]    x std-dev [m]    y std-dev [m]\n");
    for (const auto& [s, p] : log.landmarks) {
      w.field(s);
      w.field(p.x());
      w.field(p.y());
      w.field(0.0);
      w.field(0.0);
      w.endLine();
    }
    w.save(dir / "Landmark_Groundtruth.dat");
  }
  {
    Writer w(std::string(kHeaderTitle) +
             "# Odometry Data Format:\n"
             "# Time [s]    forward velocity [m/s]    angular velocity [rad/s]\n");
    for (const auto& r : log.odometry) {
      w.field(r.time);
      w.field(r.v);
      w.field(r.w);
      w.endLine();
    }
    w.save(dir / robotFile(log.robot, "Odometry"));
  }
  {
    Writer w(std::string(kHeaderTitle) +
             "# Measurement Data Format:\n"
             "# Time [s]    Barcode #    range [m]    bearing [rad]\n");
    for (const auto& m : log.measurements) {
      w.field(m.time);
      w.field(kBarcodeOffset + m.subject);
      w.field(m.range);
      w.field(m.bearing);
      w.endLine();
    }
    w.save(dir / robotFile(log.robot, "Measurement"));
  }
  const fs::path gt_path = dir / robotFile(log.robot, "Groundtruth");
  if (!log.groundtruth.empty()) {
    Writer w(std::string(kHeaderTitle) +
             "# Robot Groundtruth Data Format:\n"
             "# Time [s]    x [m]    y [m]    orientation [rad]\n");
    for (const auto& g : log.groundtruth) {
      w.field(g.time);
      w.field(g.pose.x());
      w.field(g.pose.y());
      w.field(g.pose.z());
      w.endLine();
    }
    w.save(gt_path);
  } else {
    fs::remove(gt_path, ec);  // a stale ground truth of this robot would be read back
  }
  if (log.noise) {
    const NoiseModel& n = *log.noise;
    const nlohmann::json j = {{"format", "seif-mrclam"},
                              {"robot", log.robot},
                              {"noise",
                               {{"sigma_v", n.sigma_v},
                                {"sigma_w", n.sigma_w},
                                {"sigma_range", n.sigma_range},
                                {"sigma_bearing", n.sigma_bearing}}}};
    Writer w(j.dump(2) + "\n");
    w.save(dir / "meta.json");
  }
}

}  // namespace seif
