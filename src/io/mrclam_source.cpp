// The MRCLAM layout as a streaming EventSource (include/seif/io/mrclam_source.hpp).
#include "io/mrclam_source.hpp"
#include <seif/models/range_bearing.hpp>

#include "mrclam_rows.hpp"

#include <cmath>
#include <limits>

namespace seif {
namespace {

namespace fs = std::filesystem;
constexpr double kNever = std::numeric_limits<double>::infinity();

std::string robotFile(int robot, const char* kind) {
  std::string s("Robot");
  s.append(std::to_string(robot)).append("_").append(kind).append(".dat");
  return s;
}

/// Opens file `name` of the folder as a table; nullopt when absent.
using Opener = std::function<std::optional<TextTable>(const std::string& name)>;

class MrclamSource final : public EventSource {
 public:
  MrclamSource(const std::string& folder, const Opener& open, const DatasetOptions& options,
               const std::optional<std::string>& meta, std::size_t bytes)
      : robot_(options.robot), bytes_(bytes) {
    if (robot_ < 1 || robot_ > 5) {
      throw DataError(folder, 0, "robot number " + std::to_string(robot_) + " is outside 1..5");
    }
    const auto required = [&](const std::string& name) {
      std::optional<TextTable> t = open(name);
      if (!t) throw DataError((fs::path(folder) / name).string(), 0, "missing required file");
      return std::move(*t);
    };
    {
      TextTable t = required("Barcodes.dat");
      barcodes_ = parseBarcodes(t);
    }
    {
      TextTable t = required("Landmark_Groundtruth.dat");
      info_.landmarks = parseLandmarks(t);
    }
    odometry_ = required(robotFile(robot_, "Odometry"));
    measurements_ = required(robotFile(robot_, "Measurement"));
    groundtruth_ = open(robotFile(robot_, "Groundtruth"));
    info_.source = folder;
    info_.format = "mrclam";
    info_.has_groundtruth = groundtruth_.has_value();
    resolveModels(folder, options, meta);
    advanceOdometry();
    advanceMeasurement();
    advanceGroundtruth();
    startPose(open);
  }

  const DatasetInfo& info() const override { return info_; }
  double progress() const override {
    return bytes_ == 0 ? 1.0 : std::min(1.0, static_cast<double>(odometry_->offset()) / static_cast<double>(bytes_));
  }
  std::map<std::string, std::size_t> dropped() const override {
    return {{"robot_measurements", dropped_.robot_measurements}, {"unknown_barcodes", dropped_.unknown_barcodes}};
  }

  bool next(Event& event) override {
    const double t = std::min({odometry_time_, measurement_time_, groundtruth_time_});
    if (t == kNever) return false;
    if (measurement_time_ == t) {
      ObservationEvent obs{t, {}};
      while (measurement_time_ == t) {
        obs.observations.push_back(observationOf(measurement_));
        advanceMeasurement();
      }
      event = std::move(obs);
    } else if (odometry_time_ == t) {
      event = ControlEvent{t, VelocityControl{odometry_row_.v, odometry_row_.w, 0.0}};
      advanceOdometry();
    } else {
      event = groundtruth_row_;
      advanceGroundtruth();
    }
    return true;
  }

 private:
  void resolveModels(const std::string& folder, const DatasetOptions& options, const std::optional<std::string>& meta) {
    checkNoiseNames(options, {"sigma_v", "sigma_w", "sigma_range", "sigma_bearing"}, "mrclam");
    const std::string meta_name = (fs::path(folder) / "meta.json").string();
    const std::optional<NoiseModel> file = meta ? readMetaJson(*meta, meta_name) : std::nullopt;
    // A simulated folder's noise is per step (the simulator's); the real robots' is a rate.
    const NoiseForm form = options.noise_form.value_or(file ? NoiseForm::PerStep : NoiseForm::Rate);
    const bool rate = form == NoiseForm::Rate;
    NoiseModel d = mrclamDefaultNoise();
    if (rate) {
      d.sigma_v *= std::sqrt(kMrclamOdometryPeriod);
      d.sigma_w *= std::sqrt(kMrclamOdometryPeriod);
    }
    const auto from = [&](double NoiseModel::*m) { return file ? std::optional<double>((*file).*m) : std::nullopt; };
    const double sv = resolveNoise(info_, options, "sigma_v", rate ? "m/s*sqrt(s)" : "m/s", from(&NoiseModel::sigma_v), meta_name, d.sigma_v);
    const double sw = resolveNoise(info_, options, "sigma_w", rate ? "rad/s*sqrt(s)" : "rad/s", from(&NoiseModel::sigma_w), meta_name, d.sigma_w);
    const double sr = resolveNoise(info_, options, "sigma_range", "m", from(&NoiseModel::sigma_range), meta_name, d.sigma_range);
    const double sb = resolveNoise(info_, options, "sigma_bearing", "rad", from(&NoiseModel::sigma_bearing), meta_name, d.sigma_bearing);
    info_.motion = std::make_shared<VelocityModel>(sv, sw, form);
    info_.sensor = std::make_shared<RangeBearingModel>(sr, sb);
  }

  /// The ground truth interpolated at the first odometry stamp (a second cursor on the file).
  void startPose(const Opener& open) {
    info_.start_pose_source = "origin: the log has no ground truth";
    if (!groundtruth_ || odometry_time_ == kNever || groundtruth_time_ == kNever) return;
    std::optional<TextTable> t = open(robotFile(robot_, "Groundtruth"));
    TimeOrder order;
    std::vector<TimedPose> span;  // at most the two rows around the first odometry stamp
    while (t->next()) {
      span.push_back(groundtruthRow(*t, order));
      if (span.size() > 2) span.erase(span.begin());
      if (span.back().time >= odometry_time_) break;
    }
    info_.start_pose = interpolatePose(span, odometry_time_);
    info_.start_pose_source = startPoseFromGroundTruth(span, odometry_time_) + " (" + robotFile(robot_, "Groundtruth") + ")";
  }

  void advanceOdometry() {
    if (odometry_->next()) {
      odometry_row_ = odometryRow(*odometry_, odometry_order_);
      odometry_time_ = odometry_row_.time;
    } else {
      odometry_time_ = kNever;
    }
  }
  void advanceMeasurement() {
    while (measurements_->next()) {
      if (const auto m = measurementRow(*measurements_, measurement_order_, barcodes_, dropped_)) {
        measurement_ = *m;
        measurement_time_ = m->time;
        return;
      }
    }
    measurement_time_ = kNever;
  }
  void advanceGroundtruth() {
    if (groundtruth_ && groundtruth_->next()) {
      groundtruth_row_ = groundtruthRow(*groundtruth_, groundtruth_order_);
      groundtruth_time_ = groundtruth_row_.time;
    } else {
      groundtruth_time_ = kNever;
    }
  }

  int robot_;
  std::size_t bytes_;
  DatasetInfo info_;
  Barcodes barcodes_;
  DropCounts dropped_;
  std::optional<TextTable> odometry_, measurements_, groundtruth_;
  TimeOrder odometry_order_, measurement_order_, groundtruth_order_;
  OdometryRecord odometry_row_;
  MeasurementRecord measurement_;
  TimedPose groundtruth_row_;
  double odometry_time_ = kNever, measurement_time_ = kNever, groundtruth_time_ = kNever;
};

}  // namespace

NoiseModel mrclamDefaultNoise() {
  // Measured on dataset 6 against Vicon: 1-s means of the velocity commands differ from the
  // true velocities by 0.013 m/s and 0.038 rad/s; range residuals have a robust sd of
  // 0.08-0.18 m with a heavy tail, bearing residuals 0.006-0.012 rad. The values were then
  // chosen among a small grid by the EKF's errors over the five robots (README, "MRCLAM").
  return {0.05, 0.2, 0.2, 0.03};
}

bool looksLikeMrclam(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec) || !fs::exists(path / "Barcodes.dat", ec)) return false;
  for (int r = 1; r <= 5; ++r) {
    if (fs::exists(path / robotFile(r, "Odometry"), ec)) return true;
  }
  return false;
}

std::unique_ptr<EventSource> openMrclam(const fs::path& dir, const DatasetOptions& options) {
  const std::string folder = dir.string();
  std::error_code ec;
  const auto bytes = fs::file_size(dir / robotFile(options.robot, "Odometry"), ec);
  return std::make_unique<MrclamSource>(
      folder,
      [&](const std::string& name) -> std::optional<TextTable> {
        if (!regularFileExists(dir / name)) return std::nullopt;
        return TextTable::open(dir / name);
      },
      options, readFileIfExists(dir / "meta.json"), ec ? 0 : bytes);
}

std::unique_ptr<EventSource> openMrclam(const MrclamFiles& files, const DatasetOptions& options) {
  const auto meta = files.text.find("meta.json");
  const auto odo = files.text.find(robotFile(options.robot, "Odometry"));
  return std::make_unique<MrclamSource>(
      files.folder,
      [&](const std::string& name) -> std::optional<TextTable> {
        const auto it = files.text.find(name);
        if (it == files.text.end()) return std::nullopt;
        return TextTable((fs::path(files.folder) / name).string(), it->second);
      },
      options, meta == files.text.end() ? std::nullopt : std::optional<std::string>(meta->second),
      odo == files.text.end() ? 0 : odo->second.size());
}

}  // namespace seif
