#pragma once
// The MRCLAM layout (io/mrclam.hpp) as a streaming EventSource: Barcodes.dat,
// Landmark_Groundtruth.dat and meta.json are small and read whole; RobotN_Odometry.dat,
// _Measurement.dat and _Groundtruth.dat are read line by line and merged by time, so memory
// does not grow with the log. Same checks and messages as readMrclam.
//
// Events: a ControlEvent{VelocityControl} per odometry row, an ObservationEvent per
// measurement stamp (barcodes mapped to subjects; measurements of robots and unknown
// barcodes dropped and counted), a TimedPose per ground-truth row. At equal stamps:
// observations, then the control, then ground truth.
// Start pose: the ground truth interpolated at the first odometry stamp (clamped to the
// first ground-truth pose when it starts later), else the origin.
// Noise (names sigma_v, sigma_w, sigma_range, sigma_bearing): the command line's, else
// meta.json's (a simulated folder: per-step form, as the simulator draws it), else the real
// robots' defaults, in the rate form (README "MRCLAM").
#include <seif/io/event_source.hpp>
#include <seif/io/mrclam.hpp>

namespace seif {

/// A folder holding Barcodes.dat and a RobotN_Odometry.dat.
bool looksLikeMrclam(const std::filesystem::path& path);

std::unique_ptr<EventSource> openMrclam(const std::filesystem::path& dir, const DatasetOptions& options);
/// The same on files in memory (`files` must outlive the source).
std::unique_ptr<EventSource> openMrclam(const MrclamFiles& files, const DatasetOptions& options);

/// The real MRCLAM robots' noise, per step at the ~67 Hz odometry rate (README "MRCLAM"):
/// sigma_v 0.05 m/s, sigma_w 0.2 rad/s, sigma_range 0.2 m, sigma_bearing 0.03 rad.
NoiseModel mrclamDefaultNoise();
/// Odometry period the per-step defaults were tuned at: rate sigma = step sigma * sqrt(it).
inline constexpr double kMrclamOdometryPeriod = 1.0 / 67.0;

}  // namespace seif
