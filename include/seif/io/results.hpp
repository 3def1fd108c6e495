#pragma once
// Result files of a run: trajectory.tum (TUM format, read by evo and most SLAM tools),
// map.csv (id, x, y, and the 2x2 marginal covariance), the dataset's GPS fixes (gps.csv) and
// ground-truth landmarks (landmarks_groundtruth.csv). Both are written atomically
// (AtomicFile): complete, or absent.
#include <seif/filters/slam_filter.hpp>
#include <seif/core/dataset.hpp>

#include <filesystem>
#include <map>
#include <vector>

namespace seif {

/// "timestamp tx ty tz qx qy qz qw" per line; z = 0 and the quaternion is the yaw rotation.
void writeTum(const std::filesystem::path& file, const std::vector<TimedPose>& trajectory);

/// trajectory_cov.csv: time and the upper triangle of each pose's covariance
/// (time,cov_xx,cov_xy,cov_xt,cov_yy,cov_yt,cov_tt; t = heading), one row per trajectory pose.
void writeTrajectoryCovariance(const std::filesystem::path& file, const std::vector<TimedPose>& trajectory,
                               const std::vector<Mat3>& covariances);

/// gps.csv: header "time,x,y", one row per GPS fix as the dataset gave it (metres, the
/// dataset's local frame).
void writeGpsCsv(const std::filesystem::path& file, const std::vector<GpsFix>& fixes);

/// landmarks_groundtruth.csv: header "id,x,y", one row per ground-truth landmark by id (the
/// dataset's ids and frame).
void writeLandmarkTruthCsv(const std::filesystem::path& file, const std::map<int, Vec2>& landmarks);

/// What writeMapCsv does with a landmark whose estimate (or covariance) is not finite.
enum class NonFiniteRows {
  Refuse,  ///< throw NumericError naming the landmark; nothing written
  Omit,    ///< leave its row out (the map of a failed run, whose failure is reported)
};

/// Header "id,x,y,cov_xx,cov_xy,cov_yy", one row per mapped landmark in map order; without
/// `covariances`, "id,x,y" (the marginals cost the SEIF a sparse factorisation: memory
/// beyond the filter's at 10^6 landmarks, README "Scale"). A NaN is never written.
void writeMapCsv(const std::filesystem::path& file, const SlamFilter& filter, bool covariances = true,
                 NonFiniteRows non_finite = NonFiniteRows::Refuse);

}  // namespace seif
