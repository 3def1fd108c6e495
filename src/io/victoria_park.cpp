// Reader of the Victoria Park folder (include/seif/io/victoria_park.hpp).
#include "io/text_table.hpp"
#include "io/victoria_park.hpp"
#include <seif/models/range_bearing.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

namespace seif {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
constexpr double kNever = std::numeric_limits<double>::infinity();

// Default noise (documented in the README, "Victoria Park"). Not tuned on GPS: the published
// settings (README of the data: control sigma_v 0.02-0.8 m/s and steering 1.8-2 deg per
// 40 Hz step; range 0.1 m + 1 % to 1.5 m; bearing 1-2.8 deg), taken near the middle and
// converted to noise densities at the 40 Hz control period: sigma_rate = sigma_step sqrt(0.025 s).
constexpr double kControlPeriod = 0.025;
const double kSigmaSpeed = 0.5 * std::sqrt(kControlPeriod);                    // 0.5 m/s per step
const double kSigmaSteering = 2.0 * kPi / 180.0 * std::sqrt(kControlPeriod);   // 2 deg per step
constexpr double kSigmaRange = 0.5;                                            // m
constexpr double kSigmaBearing = 2.0 * kPi / 180.0;                            // 2 deg

/// One file's cursor: the next row parsed, or none at the end.
struct Cursor {
  std::optional<TextTable> table;
  TimeOrder order;
  double time = kNever;  // stamp of the row held, kNever at the end
};

constexpr const char* kAssociated = "tree_observations_associated_UTS.txt";
constexpr const char* kRaw = "tree_detections.txt";
const std::initializer_list<const char*> kAssociatedColumns = {"time", "range", "angle_laser", "feature_id", "x_est", "y_est"};
const std::initializer_list<const char*> kRawColumns = {"time", "scan_index", "range", "angle_laser", "diameter"};

/// The laser angle of column `col` in [0, pi]. A value within its printed precision (half a
/// unit of the last decimal written) of [0, pi] is clamped into it: 3.141593 is pi as printed.
double laserAngle(const TextTable& r, std::size_t col) {
  const double angle = r.real(col);
  if (angle >= 0.0 && angle <= kPi) return angle;
  const double h = r.halfUnit(col);
  if (angle < -h || angle > kPi + h) {
    r.fail("laser angle " + formatDouble(angle) + " is outside [0, pi] (beyond its printed precision " +
           formatDouble(h) + ")");
  }
  return std::clamp(angle, 0.0, kPi);
}

/// A row of the UTS file, checked: (range, angle, feature id).
struct AssociatedRow {
  double range = 0.0, angle = 0.0;
  int id = kUnknownLandmark;
  double range_half = 0.0, angle_half = 0.0;  // printed precision, for matching raw detections
  bool used = false;
};

AssociatedRow associatedRow(const TextTable& r) {
  AssociatedRow a;
  a.range = r.range(1);
  a.angle = laserAngle(r, 2);
  const long long id = r.index(3);
  r.real(4);  // the distributor's estimate: checked, not used
  r.real(5);
  if (id > std::numeric_limits<int>::max()) r.fail("feature id " + std::to_string(id) + " is too large");
  a.id = static_cast<int>(id);
  a.range_half = r.halfUnit(1);
  a.angle_half = r.halfUnit(2);
  return a;
}

class VictoriaParkSource final : public EventSource {
 public:
  using Opener = std::function<std::optional<TextTable>(const char* name)>;

  VictoriaParkSource(const std::string& folder, const Opener& open, std::size_t controls_size,
                     const DatasetOptions& options)
      : raw_(options.detections == Detections::Raw), controls_size_(controls_size) {
    checkNoiseNames(options, {"sigma_speed", "sigma_steering", "sigma_range", "sigma_bearing"}, "victoria-park");
    info_.source = folder;
    info_.format = "victoria-park";
    const NoiseForm form = options.noise_form.value_or(NoiseForm::Rate);
    const bool rate = form == NoiseForm::Rate;
    const double s_speed = resolveNoise(info_, options, "sigma_speed", rate ? "m/s*sqrt(s)" : "m/s", {}, "", kSigmaSpeed);
    const double s_steer = resolveNoise(info_, options, "sigma_steering", rate ? "rad*sqrt(s)" : "rad", {}, "", kSigmaSteering);
    const double s_range = resolveNoise(info_, options, "sigma_range", "m", {}, "", kSigmaRange);
    const double s_bearing = resolveNoise(info_, options, "sigma_bearing", "rad", {}, "", kSigmaBearing);
    info_.motion = std::make_shared<AckermannModel>(victoriaParkGeometry(), s_speed, s_steer, form);
    info_.sensor = std::make_shared<RangeBearingModel>(s_range, s_bearing);  // at the state: the laser
    info_.start_pose_source = "origin, heading 0: the dataset gives no initial pose (GPS is compared after a rigid alignment)";
    const char* detections = raw_ ? kRaw : kAssociated;
    controls_.table = open("controls.txt");
    observations_.table = open(detections);
    if (!controls_.table) throw DataError((fs::path(folder) / "controls.txt").string(), 0, "missing required file");
    if (!observations_.table) throw DataError((fs::path(folder) / detections).string(), 0, "missing required file");
    if (raw_) truth_.table = open(kAssociated);  // optional: only to score an association
    gps_.table = open("gps.txt");
    info_.has_gps = gps_.table.has_value();
    advance(controls_, {"time", "speed", "steering"});
    advance(observations_, raw_ ? kRawColumns : kAssociatedColumns);
    advance(truth_, kAssociatedColumns);
    advance(gps_, {"time", "x", "y"});
  }

  const DatasetInfo& info() const override { return info_; }
  double progress() const override {
    if (controls_size_ == 0 || !controls_.table) return 1.0;
    return std::min(1.0, static_cast<double>(controls_read_) / static_cast<double>(controls_size_));
  }
  std::map<std::string, std::size_t> dropped() const override {
    if (!raw_ || !truth_.table) return {};
    return {{"associated_rows_without_raw_detection", unmatched_truth_}};
  }

  bool next(Event& event) override {
    const double t = std::min({controls_.time, observations_.time, gps_.time});
    if (t == kNever) {
      if (raw_) truthWindow(kNever);  // counts the UTS rows no detection matched
      return false;
    }
    if (observations_.time == t) {
      ObservationEvent obs{t, {}};
      if (raw_) truthWindow(t);
      while (observations_.time == t) {
        const TextTable& r = *observations_.table;
        if (raw_) {
          checkScanIndex(r, r.index(1), obs.observations.empty());
          const double range = r.range(2), angle = laserAngle(r, 3);
          const double diameter = r.real(4);  // checked, not used
          if (diameter < 0.0) r.fail("diameter " + formatDouble(diameter) + " must not be negative");
          Observation z{kUnknownLandmark, Vec2(range, angle - kPi / 2), std::nullopt};
          z.truth = matchTruth(range, angle, r.halfUnit(2), r.halfUnit(3));
          obs.observations.push_back(z);
        } else {
          const AssociatedRow a = associatedRow(r);
          obs.observations.push_back({a.id, Vec2(a.range, a.angle - kPi / 2), std::nullopt, a.id});
        }
        advance(observations_, raw_ ? kRawColumns : kAssociatedColumns);
      }
      event = std::move(obs);
    } else if (controls_.time == t) {
      const TextTable& r = *controls_.table;
      const double speed = r.real(1), steering = r.real(2);
      if (std::abs(steering) >= kPi / 2) r.fail("steering " + formatDouble(steering) + " is not in (-pi/2, pi/2)");
      if (std::abs(speed) > kMaxSpeed) r.fail("speed " + formatDouble(speed) + " m/s is beyond 10^3 m/s");
      event = ControlEvent{t, AckermannControl{speed, steering, 0.0}};
      ++controls_read_;
      advance(controls_, {"time", "speed", "steering"});
    } else {
      const TextTable& r = *gps_.table;
      const Vec2 fix(r.real(1), r.real(2));
      // Local metres: beyond the Earth's size a fix is a corrupt value (its square, in the
      // GPS error, would overflow).
      if (fix.cwiseAbs().maxCoeff() > 1e8) r.fail("GPS fix (" + formatDouble(fix.x()) + ", " + formatDouble(fix.y()) + ") is not in local metres");
      event = GpsFix{t, fix};
      advance(gps_, {"time", "x", "y"});
    }
    return true;
  }

 private:
  static void advance(Cursor& c, std::initializer_list<const char*> columns) {
    if (!c.table || !c.table->next()) {
      c.time = kNever;
      return;
    }
    c.table->expect(columns);
    c.time = c.table->real(0);
    c.order.check(*c.table, c.time);
  }

  /// The UTS rows stamped `t` (both files carry the laser scan's stamp), the only ones a raw
  /// detection at `t` can match; rows left behind unmatched are counted.
  void truthWindow(double t) {
    if (window_time_ == t) return;
    for (const AssociatedRow& a : window_) unmatched_truth_ += a.used ? 0 : 1;
    window_.clear();
    window_time_ = t;
    while (truth_.time < t) {  // a stamp with no raw detection
      associatedRow(*truth_.table);
      ++unmatched_truth_;
      advance(truth_, kAssociatedColumns);
    }
    while (truth_.time == t && t != kNever) {
      window_.push_back(associatedRow(*truth_.table));
      advance(truth_, kAssociatedColumns);
    }
  }

  /// The feature id of the unused UTS row at this stamp that is the same detection: range
  /// and angle equal within what both files print (the sum of their half units), nearest
  /// first; kUnknownLandmark when there is none.
  int matchTruth(double range, double angle, double range_half, double angle_half) {
    AssociatedRow* best = nullptr;
    double best_distance = kNever;
    for (AssociatedRow& a : window_) {
      if (a.used) continue;
      const auto ratio = [](double diff, double tolerance) { return diff == 0.0 ? 0.0 : diff / tolerance; };
      const double d = std::max(ratio(std::abs(range - a.range), range_half + a.range_half),
                                ratio(std::abs(angle - a.angle), angle_half + a.angle_half));
      constexpr double kSlack = 1.0 + 1e-9;  // the decimal values rounded to binary
      if (d <= kSlack && d < best_distance) {
        best = &a;
        best_distance = d;
      }
    }
    if (!best) return kUnknownLandmark;
    best->used = true;
    return best->id;
  }

  bool raw_ = false;
  DatasetInfo info_;
  Cursor controls_, observations_, gps_;
  Cursor truth_;  // raw: the UTS file, read alongside for the truth ids
  std::vector<AssociatedRow> window_;
  double window_time_ = -kNever;
  std::size_t unmatched_truth_ = 0;
  long long scan_ = -1;  // the raw file's scan index of the stamp read last

  /// The scan index is not used, but it tells a corrupt file: one stamp is one scan, so the
  /// rows of a stamp share it and a later stamp has a larger one.
  void checkScanIndex(const TextTable& r, long long scan, bool first_of_stamp) {
    if (first_of_stamp) {
      if (scan <= scan_) r.fail("scan index " + std::to_string(scan) + " does not follow the scan before it (" + std::to_string(scan_) + ")");
      scan_ = scan;
    } else if (scan != scan_) {
      r.fail("scan index " + std::to_string(scan) + " differs from the " + std::to_string(scan_) + " of the rows before it at the same time");
    }
  }
  std::size_t controls_size_ = 0;  // rows (memory) or bytes (file) of controls.txt, for progress()
  std::size_t controls_read_ = 0;
};

}  // namespace

AckermannGeometry victoriaParkGeometry() { return {2.83, 0.76, Vec2(3.78, 0.50)}; }

bool looksLikeVictoriaPark(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) && fs::exists(path / "controls.txt", ec) &&
         (fs::exists(path / kAssociated, ec) || fs::exists(path / kRaw, ec));
}

std::unique_ptr<EventSource> openVictoriaPark(const fs::path& dir, const DatasetOptions& options) {
  std::size_t rows = 0;
  if (regularFileExists(dir / "controls.txt")) {
    // Rows, counted by a first pass over the file (constant memory): for the progress bar.
    TextTable t = TextTable::open(dir / "controls.txt");
    while (t.next()) ++rows;
  }
  return std::make_unique<VictoriaParkSource>(
      dir.string(),
      [&](const char* name) -> std::optional<TextTable> {
        if (!regularFileExists(dir / name)) return std::nullopt;
        return TextTable::open(dir / name);
      },
      rows, options);
}

std::unique_ptr<EventSource> openVictoriaPark(const VictoriaParkFiles& files, const DatasetOptions& options) {
  std::size_t rows = 0;
  if (const auto it = files.text.find("controls.txt"); it != files.text.end()) {
    TextTable t("controls.txt", it->second);
    while (t.next()) ++rows;
  }
  return std::make_unique<VictoriaParkSource>(
      files.folder,
      [&](const char* name) -> std::optional<TextTable> {
        const auto it = files.text.find(name);
        if (it == files.text.end()) return std::nullopt;
        return TextTable((fs::path(files.folder) / name).string(), it->second);
      },
      rows, options);
}

}  // namespace seif
