#include <seif/core/errors.hpp>
#include "core/files.hpp"
#include <seif/io/results.hpp>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace seif {

void writeTum(const std::filesystem::path& file, const std::vector<TimedPose>& trajectory) {
  AtomicFile f(file);
  std::fprintf(f.get(), "# timestamp tx ty tz qx qy qz qw\n");
  for (const TimedPose& p : trajectory) {
    const double half = 0.5 * p.pose.z();
    std::fprintf(f.get(), "%.6f %.9g %.9g 0 0 0 %.9g %.9g\n", p.time, p.pose.x(), p.pose.y(),
                 std::sin(half), std::cos(half));
  }
  f.commit();
}

void writeGpsCsv(const std::filesystem::path& file, const std::vector<GpsFix>& fixes) {
  AtomicFile f(file);
  std::fprintf(f.get(), "time,x,y\n");
  for (const GpsFix& g : fixes) std::fprintf(f.get(), "%.6f,%.9g,%.9g\n", g.time, g.position.x(), g.position.y());
  f.commit();
}

void writeLandmarkTruthCsv(const std::filesystem::path& file, const std::map<int, Vec2>& landmarks) {
  AtomicFile f(file);
  std::fprintf(f.get(), "id,x,y\n");
  for (const auto& [id, p] : landmarks) std::fprintf(f.get(), "%d,%.9g,%.9g\n", id, p.x(), p.y());
  f.commit();
}

void writeTrajectoryCovariance(const std::filesystem::path& file, const std::vector<TimedPose>& trajectory,
                               const std::vector<Mat3>& covariances) {
  if (trajectory.size() != covariances.size()) {
    throw InvalidArgument("writeTrajectoryCovariance: " + std::to_string(trajectory.size()) + " poses but " +
                                std::to_string(covariances.size()) + " covariances");
  }
  AtomicFile f(file);
  std::fprintf(f.get(), "time,cov_xx,cov_xy,cov_xt,cov_yy,cov_yt,cov_tt\n");
  for (std::size_t k = 0; k < trajectory.size(); ++k) {
    const Mat3& P = covariances[k];
    std::fprintf(f.get(), "%.6f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", trajectory[k].time, P(0, 0), P(0, 1), P(0, 2),
                 P(1, 1), P(1, 2), P(2, 2));
  }
  f.commit();
}

void writeMapCsv(const std::filesystem::path& file, const SlamFilter& filter, bool covariances,
                 NonFiniteRows non_finite) {
  AtomicFile f(file);
  std::fprintf(f.get(), covariances ? "id,x,y,cov_xx,cov_xy,cov_yy\n" : "id,x,y\n");
  for (int id : filter.landmarkIds()) {
    const Vec2 y = filter.landmark(id);
    const Mat2 P = covariances ? filter.landmarkCovariance(id) : Mat2::Zero();
    if (!y.allFinite() || !P.allFinite()) {
      if (non_finite == NonFiniteRows::Omit) continue;
      throw NumericError(file.filename().string() + ": landmark " + std::to_string(id) + "'s " +
                         (y.allFinite() ? "covariance" : "estimate") + " is not finite");
    }
    if (!covariances) {
      std::fprintf(f.get(), "%d,%.9g,%.9g\n", id, y.x(), y.y());
      continue;
    }
    std::fprintf(f.get(), "%d,%.9g,%.9g,%.9g,%.9g,%.9g\n", id, y.x(), y.y(), P(0, 0), P(0, 1),
                 P(1, 1));
  }
  f.commit();
}

}  // namespace seif
