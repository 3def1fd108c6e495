// Reader and writer of the UTIAS MRCLAM layout (include/seif/io/mrclam.hpp,
// ../shared/data/README.md). Files are read whole and parsed with std::from_chars: the
// 62k-line odometry files of dataset 6 take a few milliseconds.
#include <seif/core/errors.hpp>
#include <seif/io/atomic_file.hpp>
#include <seif/io/mrclam.hpp>

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

/// The text of `path`; nullopt when it does not exist (a dangling link included). Throws
/// DataError naming the file when it exists but cannot be read.
std::optional<std::string> readFileIfExists(const fs::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) return std::nullopt;
  if (ec == std::errc::too_many_symbolic_link_levels) {
    throw DataError(name, 0, "symbolic-link loop: " + ec.message());
  }
  if (ec) throw DataError(name, 0, "cannot access file: " + ec.message());
  if (!fs::is_regular_file(status)) throw DataError(name, 0, "not a regular file");
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

/// File `name` of `folder` as named in messages.
std::string fileName(std::string_view folder, std::string_view name) {
  return (fs::path(folder) / name).string();
}

/// One whitespace-separated table: iterates over the data lines of a file, checks the field
/// count, and parses fields strictly. Every failure is a DataError naming file and line.
/// The table refers to `folder`, `name` and `text`, which must outlive it.
class Table {
 public:
  Table(std::string_view folder, std::string_view name, std::string_view text,
        std::initializer_list<const char*> columns)
      : folder_(folder), name_(name), text_(text), count_(columns.size()) {
    assert(count_ <= kMaxColumns);
    std::copy(columns.begin(), columns.end(), columns_.begin());
  }

  long line() const { return line_; }

  /// An upper bound of the number of data lines (for reserve()).
  std::size_t lineBound() const {
    std::size_t n = 1;
    for (std::size_t i = text_.find('\n'); i != std::string_view::npos; i = text_.find('\n', i + 1)) {
      ++n;
    }
    return n;
  }

  /// Advances to the next data line; false at the end of the file.
  bool next() {
    while (pos_ < text_.size()) {
      std::size_t eol = text_.find('\n', pos_);
      if (eol == std::string_view::npos) eol = text_.size();
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

  [[noreturn]] void fail(const std::string& what) const {
    throw DataError(fileName(folder_, name_), line_, what);
  }

  /// "column 3 (range)"
  std::string columnName(std::size_t col) const {
    return "column " + std::to_string(col + 1) + " (" + columns_[col] + ")";
  }

 private:
  static bool isBlank(char c) {
    switch (c) {
      case ' ': case '\t': case '\r': case '\v': case '\f': return true;
      default: return false;
    }
  }

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
      if (n < count_) fields_[n] = line.substr(start, i - start);
      ++n;
    }
    if (n == 0) return false;
    if (n != count_) {
      std::string names;
      for (std::size_t c = 0; c < count_; ++c) {
        if (!names.empty()) names += ' ';
        names += columns_[c];
      }
      fail("expected " + std::to_string(count_) + " fields (" + names + "), found " +
           std::to_string(n));
    }
    return true;
  }

  std::string_view folder_;
  std::string_view name_;
  std::string_view text_;
  static constexpr std::size_t kMaxColumns = 5;
  std::size_t count_;  // columns
  std::array<const char*, kMaxColumns> columns_{};
  std::array<std::string_view, kMaxColumns> fields_{};
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

  // Barcodes.dat: subject barcode.
  struct BarcodeRow {
    int subject;
    long line;
  };
  std::map<int, BarcodeRow> barcodes;
  {
    Table t(folder, "Barcodes.dat", required("Barcodes.dat"), {"subject", "barcode"});
    std::map<int, long> subject_line;
    while (t.next()) {
      const int subject = t.integer(0);
      const int barcode = t.integer(1);
      if (subject < 1) t.fail("subject number " + std::to_string(subject) + " must be positive");
      if (barcode < 0) t.fail("barcode " + std::to_string(barcode) + " must not be negative");
      if (const auto [it, fresh] = barcodes.emplace(barcode, BarcodeRow{subject, t.line()}); !fresh) {
        t.fail("barcode " + std::to_string(barcode) + " listed twice (first on line " +
               std::to_string(it->second.line) + ")");
      }
      if (const auto [it, fresh] = subject_line.emplace(subject, t.line()); !fresh) {
        t.fail("subject " + std::to_string(subject) + " listed twice (first on line " +
               std::to_string(it->second) + ")");
      }
    }
  }

  // Landmark_Groundtruth.dat: subject x y x_sd y_sd.
  {
    Table t(folder, "Landmark_Groundtruth.dat", required("Landmark_Groundtruth.dat"),
            {"subject", "x", "y", "x_sd", "y_sd"});
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
    const std::string name = robotFile(robot, "Odometry");
    Table t(folder, name, required(name), {"time", "v", "w"});
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
    const std::string name = robotFile(robot, "Measurement");
    Table t(folder, name, required(name), {"time", "barcode", "range", "bearing"});
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
      const auto it = barcodes.find(barcode);
      if (it == barcodes.end()) {
        ++log.dropped.unknown_barcodes;
      } else if (isRobot(it->second.subject)) {
        ++log.dropped.robot_measurements;
      } else {
        m.subject = it->second.subject;
        log.measurements.push_back(m);
      }
    }
  }

  // RobotN_Groundtruth.dat (optional): time x y theta.
  const std::string gt_name = robotFile(robot, "Groundtruth");
  if (const std::optional<std::string_view> text = read(gt_name)) {
    Table t(folder, gt_name, *text, {"time", "x", "y", "theta"});
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
