// Reader and writer of the UTIAS MRCLAM layout (include/seif/io/mrclam.hpp,
// ../shared/data/README.md). Files are read whole and parsed with std::from_chars: the
// 62k-line odometry files of dataset 6 take a few milliseconds.
#include <seif/core/errors.hpp>
#include <seif/io/mrclam.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace seif {
namespace {

namespace fs = std::filesystem;

constexpr int kFirstRobot = 1;
constexpr int kLastRobot = 5;
constexpr int kBarcodeOffset = 100;  // writer: barcode = 100 + subject

bool isRobot(int subject) { return subject >= kFirstRobot && subject <= kLastRobot; }

std::string formatDouble(double x) {
  std::array<char, 64> buf{};
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return std::string(buf.data(), res.ptr);
}

/// A field as shown in a message: quoted, and shortened if absurdly long.
std::string quoted(std::string_view field) {
  constexpr std::size_t kMax = 40;
  if (field.size() > kMax) return "'" + std::string(field.substr(0, kMax)) + "...'";
  return "'" + std::string(field) + "'";
}

std::string readWholeFile(const fs::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    if (!fs::exists(path, ec)) throw DataError(name, 0, "missing required file");
    throw DataError(name, 0, "not a regular file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(name, 0, "cannot open file for reading");
  std::string text;
  const auto size = fs::file_size(path, ec);
  if (!ec) text.reserve(static_cast<std::size_t>(size));
  std::array<char, 1 << 16> chunk{};
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw DataError(name, 0, "read error");
  return text;
}

/// One whitespace-separated table: iterates over the data lines of a file, checks the field
/// count, and parses fields strictly. Every failure is a DataError naming file and line.
class Table {
 public:
  Table(const fs::path& path, std::initializer_list<const char*> columns)
      : file_(path.string()), text_(readWholeFile(path)), columns_(columns) {
    fields_.resize(columns_.size());
  }

  const std::string& file() const { return file_; }
  long line() const { return line_; }

  /// An upper bound of the number of data lines (for reserve()).
  std::size_t lineBound() const {
    std::size_t n = 1;
    for (const char c : text_) n += (c == '\n') ? 1 : 0;
    return n;
  }

  /// Advances to the next data line; false at the end of the file.
  bool next() {
    while (pos_ < text_.size()) {
      std::size_t eol = text_.find('\n', pos_);
      if (eol == std::string::npos) eol = text_.size();
      const std::string_view line(text_.data() + pos_, eol - pos_);
      pos_ = eol + 1;
      ++line_;
      if (split(line)) return true;
    }
    return false;
  }

  /// Column `col` (0-based) as a finite double.
  double real(std::size_t col) const {
    const std::string_view f = fields_[col];
    double value = 0.0;
    const auto res = std::from_chars(f.data(), f.data() + f.size(), value);
    if (res.ec == std::errc::result_out_of_range && res.ptr == f.data() + f.size()) {
      fail("number " + quoted(f) + " out of range in " + columnName(col));
    }
    if (res.ec != std::errc() || res.ptr != f.data() + f.size()) {
      fail("bad number " + quoted(f) + " in " + columnName(col));
    }
    if (!std::isfinite(value)) fail("non-finite number " + quoted(f) + " in " + columnName(col));
    return value;
  }

  /// Column `col` (0-based) as an int.
  int integer(std::size_t col) const {
    const std::string_view f = fields_[col];
    int value = 0;
    const auto res = std::from_chars(f.data(), f.data() + f.size(), value);
    if (res.ec != std::errc() || res.ptr != f.data() + f.size()) {
      fail("bad integer " + quoted(f) + " in " + columnName(col));
    }
    return value;
  }

  [[noreturn]] void fail(const std::string& what) const { throw DataError(file_, line_, what); }

  /// "column 3 (range)"
  std::string columnName(std::size_t col) const {
    return "column " + std::to_string(col + 1) + " (" + columns_[col] + ")";
  }

 private:
  static bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

  /// Splits a line into fields_; false for blank and comment lines.
  bool split(std::string_view line) {
    std::size_t i = 0;
    std::size_t n = 0;
    while (true) {
      while (i < line.size() && isBlank(line[i])) ++i;
      if (i == line.size()) break;
      if (n == 0 && line[i] == '#') return false;
      const std::size_t start = i;
      while (i < line.size() && !isBlank(line[i])) ++i;
      if (n < fields_.size()) fields_[n] = line.substr(start, i - start);
      ++n;
    }
    if (n == 0) return false;
    if (n != fields_.size()) {
      std::string names;
      for (const char* c : columns_) {
        if (!names.empty()) names += ' ';
        names += c;
      }
      fail("expected " + std::to_string(fields_.size()) + " fields (" + names + "), found " +
           std::to_string(n));
    }
    return true;
  }

  std::string file_;
  std::string text_;
  std::vector<const char*> columns_;
  std::vector<std::string_view> fields_;
  std::size_t pos_ = 0;
  long line_ = 0;
};

/// Time stamps within one file must not decrease.
class TimeOrder {
 public:
  void check(const Table& t, double time) {
    if (time < previous_) {
      t.fail("time " + formatDouble(time) + " goes backwards (line " +
             std::to_string(previous_line_) + " has " + formatDouble(previous_) + ")");
    }
    previous_ = time;
    previous_line_ = t.line();
  }

 private:
  double previous_ = -std::numeric_limits<double>::infinity();
  long previous_line_ = 0;
};

std::string robotFile(int robot, const char* kind) {
  return "Robot" + std::to_string(robot) + "_" + kind + ".dat";
}

NoiseModel readMetaNoise(const fs::path& path, bool& has_noise) {
  const std::string name = path.string();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(readWholeFile(path));
  } catch (const nlohmann::json::parse_error& e) {
    throw DataError(name, 0, std::string("malformed JSON: ") + e.what());
  }
  if (!j.is_object()) throw DataError(name, 0, "expected a JSON object");
  if (const auto it = j.find("format"); it != j.end()) {
    if (!it->is_string() || it->get<std::string>() != "seif-mrclam") {
      throw DataError(name, 0, "\"format\" must be \"seif-mrclam\", found " + it->dump());
    }
  }
  if (const auto it = j.find("robot"); it != j.end()) {
    const bool ok = it->is_number_integer() && it->get<long long>() >= kFirstRobot &&
                      it->get<long long>() <= kLastRobot;
    if (!ok) {
      throw DataError(name, 0, "\"robot\" must be an integer in 1..5, found " + it->dump());
    }
  }
  NoiseModel noise;
  has_noise = false;
  const auto it = j.find("noise");
  if (it == j.end()) return noise;
  if (!it->is_object()) throw DataError(name, 0, "\"noise\" must be an object");
  const std::pair<const char*, double*> sigmas[] = {{"sigma_v", &noise.sigma_v},
                                                    {"sigma_w", &noise.sigma_w},
                                                    {"sigma_range", &noise.sigma_range},
                                                    {"sigma_bearing", &noise.sigma_bearing}};
  for (const auto& [key, out] : sigmas) {
    const auto s = it->find(key);
    if (s == it->end()) throw DataError(name, 0, std::string("\"noise\" lacks \"") + key + "\"");
    if (!s->is_number()) {
      throw DataError(name, 0, std::string("\"noise.") + key + "\" must be a number, found " + s->dump());
    }
    *out = s->get<double>();
    if (!std::isfinite(*out) || *out < 0.0) {
      throw DataError(name, 0, std::string("\"noise.") + key + "\" must be finite and >= 0, found " +
                                   s->dump());
    }
  }
  has_noise = true;
  return noise;
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
  void save(const fs::path& path) const {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(text_.data(), static_cast<std::streamsize>(text_.size()));
    out.close();
    if (!out) throw DataError(path.string(), 0, "cannot write file");
  }

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
    const NoiseModel& n = *log.noise;
    for (const double s : {n.sigma_v, n.sigma_w, n.sigma_range, n.sigma_bearing}) {
      if (!std::isfinite(s) || s < 0.0) {
        throw DataError((dir / "meta.json").string(), 0, "cannot write a noise sigma that is not finite and >= 0");
      }
    }
  }
}

}  // namespace

RobotLog readMrclam(const std::filesystem::path& dir, int robot) {
  if (!isRobot(robot)) {
    throw DataError(dir.string(), 0, "robot number " + std::to_string(robot) + " is outside 1..5");
  }
  RobotLog log;
  log.source = dir.string();
  log.robot = robot;

  // Barcodes.dat: subject barcode.
  std::map<int, int> subject_of_barcode;
  {
    Table t(dir / "Barcodes.dat", {"subject", "barcode"});
    std::map<int, long> barcode_line;
    std::map<int, long> subject_line;
    while (t.next()) {
      const int subject = t.integer(0);
      const int barcode = t.integer(1);
      if (subject < 1) t.fail("subject number " + std::to_string(subject) + " must be positive");
      if (barcode < 0) t.fail("barcode " + std::to_string(barcode) + " must not be negative");
      if (const auto [it, fresh] = barcode_line.emplace(barcode, t.line()); !fresh) {
        t.fail("barcode " + std::to_string(barcode) + " listed twice (first on line " +
               std::to_string(it->second) + ")");
      }
      if (const auto [it, fresh] = subject_line.emplace(subject, t.line()); !fresh) {
        t.fail("subject " + std::to_string(subject) + " listed twice (first on line " +
               std::to_string(it->second) + ")");
      }
      subject_of_barcode.emplace(barcode, subject);
    }
  }

  // Landmark_Groundtruth.dat: subject x y x_sd y_sd.
  {
    Table t(dir / "Landmark_Groundtruth.dat", {"subject", "x", "y", "x_sd", "y_sd"});
    while (t.next()) {
      const int subject = t.integer(0);
      const double x = t.real(1);
      const double y = t.real(2);
      const double x_sd = t.real(3);
      const double y_sd = t.real(4);
      if (subject < 1) t.fail("subject number " + std::to_string(subject) + " must be positive");
      if (isRobot(subject)) t.fail("subject " + std::to_string(subject) + " is a robot (1-5), not a landmark");
      if (x_sd < 0.0 || y_sd < 0.0) t.fail("negative standard deviation");
      if (!log.landmarks.emplace(subject, Vec2(x, y)).second) {
        t.fail("landmark " + std::to_string(subject) + " listed twice");
      }
    }
  }

  // RobotN_Odometry.dat: time v w.
  {
    Table t(dir / robotFile(robot, "Odometry"), {"time", "v", "w"});
    log.odometry.reserve(t.lineBound());
    TimeOrder order;
    while (t.next()) {
      OdometryRecord r;
      r.time = t.real(0);
      r.v = t.real(1);
      r.w = t.real(2);
      order.check(t, r.time);
      log.odometry.push_back(r);
    }
  }

  // RobotN_Measurement.dat: time barcode range bearing.
  {
    Table t(dir / robotFile(robot, "Measurement"), {"time", "barcode", "range", "bearing"});
    log.measurements.reserve(t.lineBound());
    TimeOrder order;
    while (t.next()) {
      MeasurementRecord m;
      m.time = t.real(0);
      const int barcode = t.integer(1);
      m.range = t.real(2);
      m.bearing = t.real(3);
      order.check(t, m.time);
      if (!(m.range > 0.0)) t.fail("range " + formatDouble(m.range) + " must be positive");
      const auto it = subject_of_barcode.find(barcode);
      if (it == subject_of_barcode.end()) {
        ++log.dropped.unknown_barcodes;
      } else if (isRobot(it->second)) {
        ++log.dropped.robot_measurements;
      } else {
        m.subject = it->second;
        log.measurements.push_back(m);
      }
    }
  }

  // RobotN_Groundtruth.dat (optional): time x y theta.
  const fs::path gt_path = dir / robotFile(robot, "Groundtruth");
  std::error_code ec;
  if (fs::exists(gt_path, ec)) {
    Table t(gt_path, {"time", "x", "y", "theta"});
    log.groundtruth.reserve(t.lineBound());
    TimeOrder order;
    while (t.next()) {
      TimedPose p;
      p.time = t.real(0);
      p.pose = Pose2(t.real(1), t.real(2), t.real(3));
      order.check(t, p.time);
      log.groundtruth.push_back(p);
    }
  }

  // meta.json (optional).
  const fs::path meta = dir / "meta.json";
  if (fs::exists(meta, ec)) {
    bool has_noise = false;
    const NoiseModel noise = readMetaNoise(meta, has_noise);
    if (has_noise) log.noise = noise;
  }
  return log;
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
