// Readers and writer of the iSAM and g2o pose-graph formats (include/seif/io/graph_file.hpp).
#include <seif/core/errors.hpp>
#include "core/files.hpp"
#include <seif/io/graph_file.hpp>
#include "io/text_table.hpp"
#include <seif/models/cartesian.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/range_bearing.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <deque>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

namespace seif {
namespace {

namespace fs = std::filesystem;

enum class Kind { Pose, Landmark };
enum class Sensor { None, Cartesian, RangeBearing };

/// The symmetric matrix of an upper triangle read from `first` on (row by row).
template <int N>
Eigen::Matrix<double, N, N> upperTriangle(const TextTable& t, std::size_t first) {
  Eigen::Matrix<double, N, N> m;
  std::size_t c = first;
  for (int i = 0; i < N; ++i) {
    for (int j = i; j < N; ++j) m(i, j) = m(j, i) = t.real(c++);
  }
  return m;
}

/// Covariance <-> information. A diagonal matrix is inverted entry by entry, so that a round
/// trip through both formats gives its numbers back (1 / (1 / c) == c for the values of real
/// files; a cofactor inverse would not); others by Eigen's closed-form inverse.
template <int N>
Eigen::Matrix<double, N, N> invert(const Eigen::Matrix<double, N, N>& m) {
  const Eigen::Matrix<double, N, N> d = m.diagonal().asDiagonal();
  if (m == d) return m.diagonal().cwiseInverse().asDiagonal();
  return m.inverse();
}

/// The covariance a record gives: its matrix (iSAM), or the inverse of its information
/// matrix (g2o). Either must be symmetric positive definite, and its inverse finite (the
/// filters and the other format need it: 1e-310 is positive, 1 / 1e-310 is not finite).
template <int N>
Eigen::Matrix<double, N, N> recordCovariance(const TextTable& t, std::size_t first, bool information) {
  const Eigen::Matrix<double, N, N> m = upperTriangle<N>(t, first);
  const char* what = information ? "the information matrix" : "the covariance";
  if (Eigen::LLT<Eigen::Matrix<double, N, N>>(m).info() != Eigen::Success) t.fail(std::string(what) + " is not positive definite");
  const Eigen::Matrix<double, N, N> inverse = invert<N>(m);
  if (!inverse.allFinite() || Eigen::LLT<Eigen::Matrix<double, N, N>>(inverse).info() != Eigen::Success) {
    t.fail(std::string(what) + " is too close to singular for a finite " + (information ? "covariance" : "information matrix"));
  }
  return information ? inverse : m;
}

/// The first data line's tag of a file, or empty.
std::string firstTag(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return {};
  try {
    TextTable t = TextTable::open(path);
    return t.next() ? std::string(t.field(0)) : std::string();
  } catch (const DataError&) {
    return {};
  }
}

/// One reader for both formats: the differences are the tags, covariance vs information,
/// and g2o's vertices.
class GraphSource final : public EventSource {
 public:
  GraphSource(GraphFormat format, TextTable table, TextTable peek, std::size_t bytes, const DatasetOptions& options)
      : format_(format), table_(std::move(table)), bytes_(bytes), gtsam_landmarks_(options.isam_landmarks_as_gtsam) {
    const std::string_view name = graphFormatName(format);
    checkNoiseNames(options, {}, name);
    if (options.noise_form) throw InvalidArgument("the " + std::string(name) + " format has no noise form: its records carry covariances");
    info_.source = table_.name();
    info_.format = name;
    info_.motion = std::make_shared<OdometryModel>();
    info_.start_pose_source = "origin: the chain's first pose (the file gives no absolute pose)";
    info_.noise.push_back({"odometry covariance", std::nullopt, "", "each record (file)"});
    info_.noise.push_back({"landmark covariance", std::nullopt, "", "each record (file)"});
    scan(peek);
  }

  const DatasetInfo& info() const override { return info_; }
  double progress() const override {
    return bytes_ == 0 ? 1.0 : std::min(1.0, static_cast<double>(table_.offset()) / static_cast<double>(bytes_));
  }

  bool next(Event& event) override {
    while (ready_.empty()) {
      if (!table_.next()) {
        flush();
        if (ready_.empty()) return false;
        break;
      }
      parse();
    }
    event = std::move(ready_.front());
    ready_.pop_front();
    return true;
  }

 private:
  /// A first pass up to the first observation: the sensor model and (g2o) the start pose.
  void scan(TextTable& t) {
    std::unordered_map<long long, Pose2> vertices;
    bool before_edges = true;
    while (t.next()) {
      const std::string_view tag = t.field(0);
      if (tag == "VERTEX_SE2" && t.size() == 5 && before_edges) {  // one listed twice: vertex() refuses it
        vertices.emplace(t.index(1), Pose2(t.coordinate(2), t.coordinate(3), t.angle(4)));
      } else if ((tag == "ODOMETRY" || tag == "EDGE_SE2") && t.size() >= 3 && before_edges) {
        before_edges = false;
        const long long first = t.index(1);
        if (const auto it = vertices.find(first); it != vertices.end()) {
          info_.start_pose = it->second;
          info_.start_pose_source = "the VERTEX_SE2 of the chain's first pose (file)";
        }
      } else if (tag == "LANDMARK" || tag == "EDGE_SE2_XY") {
        sensor_ = Sensor::Cartesian;
        break;
      } else if (tag == "BR") {
        sensor_ = Sensor::RangeBearing;
        break;
      }
    }
    if (gtsam_landmarks_ && (format_ != GraphFormat::Isam || sensor_ != Sensor::Cartesian)) {
      throw InvalidArgument(table_.name() + ": GTSAM's reading applies to iSAM LANDMARK records, and this file has none");
    }
    if (sensor_ == Sensor::RangeBearing || gtsam_landmarks_) {
      info_.sensor = std::make_shared<RangeBearingModel>(1.0, 1.0);  // each record has its own
    } else {
      info_.sensor = std::make_shared<CartesianModel>(Mat2::Identity());  // each record has its own
    }
  }

  void flush() {
    if (pending_) {
      ready_.push_back(std::move(*pending_));
      pending_.reset();
    }
  }

  /// Records id as `kind`; an id is one kind for the whole file.
  void claim(long long id, Kind kind, std::size_t col) {
    const auto [it, fresh] = kinds_.emplace(id, kind);
    if (!fresh && it->second != kind) {
      table_.fail("id " + std::to_string(id) + " in " + table_.columnName(col) + " is used both as a pose and as a landmark");
    }
  }

  void startChain(long long id, std::size_t col) {
    if (current_ >= 0) return;
    claim(id, Kind::Pose, col);
    reached_.insert(id);
    current_ = id;
    info_.start_pose_id = id;
  }

  void odometry() {
    const bool isam = format_ == GraphFormat::Isam;
    table_.expect({isam ? "ODOMETRY" : "EDGE_SE2", "id1", "id2", "dx", "dy", "dtheta", "m11", "m12", "m13", "m22", "m23", "m33"});
    const long long from = table_.index(1), to = table_.index(2);
    startChain(from, 1);
    if (from != current_) {
      table_.fail("odometry from pose " + std::to_string(from) + " but the chain is at pose " + std::to_string(current_) +
                  ": records must be in time order (one chain, as driven)");
    }
    claim(to, Kind::Pose, 2);
    if (!reached_.insert(to).second) table_.fail("pose " + std::to_string(to) + " is reached twice: the chain must reach a new pose");
    OdometryIncrement u;
    u.delta = Vec3(table_.coordinate(3), table_.coordinate(4), table_.angle(5));
    u.covariance = recordCovariance<3>(table_, 6, !isam);
    flush();
    ++k_;
    ready_.push_back(ControlEvent{static_cast<double>(k_), u, to});
    current_ = to;
  }

  void observation(Sensor kind) {
    const bool isam = format_ == GraphFormat::Isam;
    Observation z;
    if (kind == Sensor::RangeBearing) {
      table_.expect({"BR", "pose", "landmark", "bearing", "range", "sigma_bearing", "sigma_range"});
      const double bearing = table_.angle(3), range = table_.range(4), sb = table_.real(5), sr = table_.real(6);
      if (!(sb > 0.0) || !(sr > 0.0)) table_.fail("standard deviations must be positive");
      z.z = Vec2(range, bearing);
      z.noise = diagonalNoise(sr, sb);
    } else {
      table_.expect({isam ? "LANDMARK" : "EDGE_SE2_XY", "pose", "landmark", "x", "y", "m11", "m12", "m22"});
      z.z = Vec2(table_.coordinate(3), table_.coordinate(4));
      z.noise = recordCovariance<2>(table_, 5, !isam);
      if (gtsam_landmarks_) {  // GTSAM's loader: bearing-range, sigma_b = sqrt(m11 / 10), sigma_r = sqrt(m11)
        const double range = z.z.norm();
        if (!(range > 0.0)) table_.fail("a landmark at the pose itself has no bearing (GTSAM's reading)");
        const double v = (*z.noise)(0, 0);
        z.z = Vec2(range, std::atan2(table_.real(4), table_.real(3)));
        z.noise = diagonalNoise(std::sqrt(v), std::sqrt(v / 10.0));
      }
    }
    if (kind != sensor_) {
      table_.fail("a file holds one kind of landmark observation: this " + std::string(table_.field(0)) +
                  " follows records of the other kind");
    }
    const long long pose = table_.index(1), landmark = table_.index(2);
    startChain(pose, 1);
    if (pose != current_) {
      table_.fail("observation from pose " + std::to_string(pose) + " but the chain is at pose " + std::to_string(current_) +
                  ": records must be in time order");
    }
    claim(landmark, Kind::Landmark, 2);
    if (landmark > std::numeric_limits<int>::max()) table_.fail("landmark id " + std::to_string(landmark) + " is too large");
    z.landmark = static_cast<int>(landmark);
    z.truth = z.landmark;
    if (!pending_) pending_ = ObservationEvent{static_cast<double>(k_), {}};
    pending_->observations.push_back(std::move(z));
  }

  void vertex(bool pose) {
    if (pose) {
      table_.expect({"VERTEX_SE2", "id", "x", "y", "theta"});
      claim(table_.index(1), Kind::Pose, 1);
      table_.coordinate(2);
      table_.coordinate(3);
      table_.angle(4);
    } else {
      table_.expect({"VERTEX_XY", "id", "x", "y"});
      claim(table_.index(1), Kind::Landmark, 1);
      table_.coordinate(2);
      table_.coordinate(3);
    }
    // A vertex's estimate is read once (the chain's first pose starts the run): a second one
    // for the same id would be ignored, or replace the first.
    if (const auto [it, fresh] = vertex_line_.emplace(table_.index(1), table_.line()); !fresh) {
      table_.fail("vertex " + std::to_string(it->first) + " listed twice (first on line " + std::to_string(it->second) + ")");
    }
  }

  void parse() {
    const std::string_view tag = table_.field(0);
    if (format_ == GraphFormat::Isam) {
      if (tag == "ODOMETRY") return odometry();
      if (tag == "LANDMARK") return observation(Sensor::Cartesian);
      if (tag == "BR") return observation(Sensor::RangeBearing);
      table_.fail("unknown record tag " + quotedField(tag) + " (iSAM: ODOMETRY, LANDMARK, BR)");
    }
    if (tag == "EDGE_SE2") return odometry();
    if (tag == "EDGE_SE2_XY") return observation(Sensor::Cartesian);
    if (tag == "VERTEX_SE2") return vertex(true);
    if (tag == "VERTEX_XY") return vertex(false);
    table_.fail("unknown record tag " + quotedField(tag) + " (g2o 2-D: VERTEX_SE2, VERTEX_XY, EDGE_SE2, EDGE_SE2_XY)");
  }

  GraphFormat format_;
  TextTable table_;
  std::size_t bytes_;
  bool gtsam_landmarks_;  // DatasetOptions::isam_landmarks_as_gtsam
  DatasetInfo info_;
  Sensor sensor_ = Sensor::None;
  std::unordered_map<long long, Kind> kinds_;
  std::unordered_map<long long, long> vertex_line_;  // where each vertex was listed
  std::unordered_set<long long> reached_;  // poses the chain has been at
  long long current_ = -1;  // the pose the chain is at
  long k_ = 0;              // odometry records so far: the time of the current pose
  std::optional<ObservationEvent> pending_;
  std::deque<Event> ready_;
};

std::unique_ptr<EventSource> openFile(GraphFormat format, const fs::path& file, const DatasetOptions& options) {
  std::error_code ec;
  const auto bytes = fs::file_size(file, ec);
  return std::make_unique<GraphSource>(format, TextTable::open(file), TextTable::open(file), ec ? 0 : bytes, options);
}

std::unique_ptr<EventSource> openText(GraphFormat format, const std::string& name, std::string_view text,
                                      const DatasetOptions& options) {
  return std::make_unique<GraphSource>(format, TextTable(name, text), TextTable(name, text), text.size(), options);
}

}  // namespace

bool looksLikeIsam(const fs::path& path) {
  const std::string tag = firstTag(path);
  return tag == "ODOMETRY" || tag == "LANDMARK" || tag == "BR";
}

bool looksLikeG2o(const fs::path& path) {
  const std::string tag = firstTag(path);
  return tag == "VERTEX_SE2" || tag == "VERTEX_XY" || tag == "EDGE_SE2" || tag == "EDGE_SE2_XY";
}

std::unique_ptr<EventSource> openIsam(const fs::path& file, const DatasetOptions& options) {
  return openFile(GraphFormat::Isam, file, options);
}
std::unique_ptr<EventSource> openG2o(const fs::path& file, const DatasetOptions& options) {
  return openFile(GraphFormat::G2o, file, options);
}
std::unique_ptr<EventSource> openIsamText(const std::string& name, std::string_view text, const DatasetOptions& options) {
  return openText(GraphFormat::Isam, name, text, options);
}
std::unique_ptr<EventSource> openG2oText(const std::string& name, std::string_view text, const DatasetOptions& options) {
  return openText(GraphFormat::G2o, name, text, options);
}

}  // namespace seif

namespace seif {
namespace {

class LineWriter {
 public:
  explicit LineWriter(std::FILE* f) : f_(f) {}
  LineWriter& tag(const char* t) {
    line_ = t;
    return *this;
  }
  LineWriter& operator<<(long long v) {
    line_.append(" ").append(std::to_string(v));
    return *this;
  }
  LineWriter& operator<<(double v) {
    line_.append(" ").append(formatDouble(v));
    return *this;
  }
  template <int N>
  LineWriter& upper(const Eigen::Matrix<double, N, N>& m) {
    for (int i = 0; i < N; ++i)
      for (int j = i; j < N; ++j) *this << m(i, j);
    return *this;
  }
  void end() {
    line_.push_back('\n');
    std::fwrite(line_.data(), 1, line_.size(), f_);
  }

 private:
  std::FILE* f_;
  std::string line_;
};

}  // namespace

GraphFormat parseGraphFormat(std::string_view name) {
  if (name == "isam") return GraphFormat::Isam;
  if (name == "g2o") return GraphFormat::G2o;
  throw InvalidArgument("unknown graph format '" + std::string(name) + "' (expected isam or g2o)");
}

std::string_view graphFormatName(GraphFormat format) { return format == GraphFormat::G2o ? "g2o" : "isam"; }

void writeGraph(const std::filesystem::path& file, EventSource& source, GraphFormat format) {
  const bool g2o = format == GraphFormat::G2o;
  if (dynamic_cast<const OdometryModel*>(source.info().motion.get()) == nullptr) {
    throw DataError(source.info().source, 0, "only an odometry stream (an iSAM or g2o file) converts to a pose graph");
  }
  const bool range_bearing = dynamic_cast<const RangeBearingModel*>(source.info().sensor.get()) != nullptr;
  if (g2o && range_bearing) {
    throw DataError(source.info().source, 0, "g2o's EDGE_SE2_XY is Cartesian: range-bearing (BR) records do not convert");
  }
  AtomicFile out(file);
  LineWriter w(out.get());
  const OdometryModel odometry;
  Pose2 x = source.info().start_pose;  // dead reckoning: g2o's initial estimates
  long long pose = -1;
  std::unordered_map<int, bool> placed;  // landmarks with a VERTEX_XY
  Event e;
  while (source.next(e)) {
    if (pose < 0) {
      pose = source.info().start_pose_id;
      if (pose < 0) throw DataError(source.info().source, 0, "the source does not number its poses");
      if (g2o) w.tag("VERTEX_SE2") << pose << x.x() << x.y() << x.z(), w.end();
    }
    if (const auto* c = std::get_if<ControlEvent>(&e)) {
      const auto& u = std::get<OdometryIncrement>(c->input);
      if (g2o) {
        x = odometry.apply(x, c->input);
        if (!x.allFinite()) {  // 1e308 twice is finite in the file, not in the sum
          throw DataError(source.info().source, 0, "pose " + std::to_string(c->pose) + ", the odometry chained, is not finite");
        }
        w.tag("VERTEX_SE2") << c->pose << x.x() << x.y() << x.z(), w.end();
        w.tag("EDGE_SE2") << pose << c->pose << u.delta.x() << u.delta.y() << u.delta.z();
        w.upper<3>(invert<3>(u.covariance)).end();
      } else {
        w.tag("ODOMETRY") << pose << c->pose << u.delta.x() << u.delta.y() << u.delta.z();
        w.upper<3>(u.covariance).end();
      }
      pose = c->pose;
    } else if (const auto* o = std::get_if<ObservationEvent>(&e)) {
      for (const Observation& z : o->observations) {
        const Mat2 C = source.info().sensor->noise(z);
        const long long lm = z.landmark;
        if (range_bearing) {
          w.tag("BR") << pose << lm << z.z.y() << z.z.x() << std::sqrt(C(1, 1)) << std::sqrt(C(0, 0));
          w.end();
        } else if (g2o) {
          if (!placed[z.landmark]) {
            const Vec2 y = source.info().sensor->inverse(x, z.z);
            w.tag("VERTEX_XY") << lm << y.x() << y.y(), w.end();
            placed[z.landmark] = true;
          }
          w.tag("EDGE_SE2_XY") << pose << lm << z.z.x() << z.z.y();
          w.upper<2>(invert<2>(C)).end();
        } else {
          w.tag("LANDMARK") << pose << lm << z.z.x() << z.z.y();
          w.upper<2>(C).end();
        }
      }
    }
  }
  if (pose < 0) throw DataError(source.info().source, 0, "no record to convert (odometry or observation)");
  out.commit();
}

}  // namespace seif
