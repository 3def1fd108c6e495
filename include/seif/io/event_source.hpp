#pragma once
// The reader seam (docs/architecture.md "The flow"): every dataset format is an
// EventSource that yields time-ordered events (core/dataset.hpp) and describes itself in a
// DatasetInfo: the vehicle's motion model, the sensor (with its mount), the noise used and
// where each value came from, the start pose and ground-truth landmarks when known.
// A source streams: it holds a few lines of its files, never the whole log, so a run's
// memory is the filter's. openDataset() picks the reader for a path.
#include <seif/core/dataset.hpp>
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>
#include <seif/models/velocity_model.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace seif {

/// One noise value a run uses, and where it came from ("file", "meta.json",
/// "command line", "default for <format>").
struct NoiseSetting {
  std::string name;   ///< e.g. "sigma_v"
  std::optional<double> value;  ///< none where each record carries its own (graph files)
  std::string unit;   ///< e.g. "m/s*sqrt(s)"
  std::string source;
};

struct DatasetInfo {
  std::string source;  ///< the path as given
  std::string format;  ///< "mrclam", "victoria-park", "isam", "g2o"
  std::shared_ptr<const MotionModel> motion;
  std::shared_ptr<const MeasurementModel> sensor;
  std::vector<NoiseSetting> noise;
  /// Where the filter starts, and why there ("ground truth at the first control",
  /// "first VERTEX_SE2 of the file", "origin: the dataset has no ground truth", ...).
  Pose2 start_pose = Pose2::Zero();
  std::string start_pose_source;
  long long start_pose_id = -1;   ///< id of the start pose, when the source numbers poses
  std::map<int, Vec2> landmarks;  ///< ground-truth landmark positions; may be empty
  bool has_groundtruth = false;   ///< the stream carries TimedPose events
  bool has_gps = false;           ///< the stream carries GpsFix events
};

/// Which detections a Victoria Park folder gives (io/victoria_park.hpp): Associated, the
/// UTS file's (tree_observations_associated_UTS.txt: landmark = truth = its feature id), or
/// Raw, the tree detector's (tree_detections.txt: landmark unknown, truth = the feature id
/// of the UTS row that is the same detection, when there is one).
enum class Detections { Associated, Raw };

/// "associated" | "raw"; throws InvalidArgument naming them.
Detections parseDetections(std::string_view name);
std::string_view detectionsName(Detections detections);

/// What a reader opens with. Noise values by name override the file's and the format's
/// defaults (their source becomes "command line"); a name the format does not use is an
/// error naming the names it does use.
struct DatasetOptions {
  int robot = 1;                        ///< MRCLAM: which robot's log
  std::map<std::string, double> noise;  ///< e.g. {"sigma_v", 0.05}
  /// The form of a rate-driven motion model's noise (velocity_model.hpp); the format's
  /// default when empty (simulated MRCLAM folders: per-step; recorded logs: rate).
  std::optional<NoiseForm> noise_form;
  /// iSAM `LANDMARK x y m11 m12 m22`: Cartesian (false: the point with its covariance), or
  /// as GTSAM's loader reads it (true): bearing atan2(y, x) and range hypot(x, y) with
  /// sigma_bearing = sqrt(m11 / 10) and sigma_range = sqrt(m11) (its heuristic), so that a
  /// cost is comparable with GTSAM's on the same file.
  bool isam_landmarks_as_gtsam = false;
  /// Victoria Park: the associated or the raw detections; Raw with another format is an
  /// InvalidArgument (openDataset).
  Detections detections = Detections::Associated;
};

class EventSource {
 public:
  virtual ~EventSource() = default;
  virtual const DatasetInfo& info() const = 0;
  /// The next event in time order; false at the end. Throws DataError "file:line: what".
  virtual bool next(Event& event) = 0;
  /// Fraction of the input read so far, in [0, 1] (for a progress bar).
  virtual double progress() const = 0;
  /// Records dropped so far, by reason (e.g. {"unknown_barcodes", 43}), reported, never silent.
  virtual std::map<std::string, std::size_t> dropped() const { return {}; }
};

enum class DatasetFormat { Auto, Mrclam, VictoriaPark, Isam, G2o };

/// "auto" | "mrclam" | "victoria-park" | "isam" | "g2o"; throws InvalidArgument
/// naming them.
DatasetFormat parseDatasetFormat(std::string_view name);
std::string_view datasetFormatName(DatasetFormat format);

/// Opens `path` with the reader of `format`; Auto picks it from what the path holds and,
/// when it cannot tell, throws DataError naming the path and listing every format with
/// what it looks for.
std::unique_ptr<EventSource> openDataset(const std::filesystem::path& path,
                                         DatasetFormat format = DatasetFormat::Auto,
                                         const DatasetOptions& options = {});

/// Resolves one noise value: the command line's (options), else the file's, else the
/// format's default; records it in `info.noise`. Throws InvalidArgument for a value
/// that is not finite and > 0.
double resolveNoise(DatasetInfo& info, const DatasetOptions& options, const std::string& name,
                    const std::string& unit, std::optional<double> from_file,
                    const std::string& file_source, double default_value);

/// Throws InvalidArgument when `options.noise` names a value outside `known`.
void checkNoiseNames(const DatasetOptions& options, const std::vector<std::string>& known,
                     std::string_view format);

}  // namespace seif
