#pragma once
// Reader of the Victoria Park folder (Guivant & Nebot 2001; ../shared/data/README.md):
//   controls.txt                          time speed steering    (40 Hz; rear-left encoder, front wheels)
//   tree_observations_associated_UTS.txt  time range angle_laser feature_id x_est y_est
//                                         (known association, Huang et al.; x_est, y_est unused)
//   gps.txt                               time x y               (optional; failing unit: gaps, jumps)
// tree_detections.txt (raw detections, no association) is for unknown data association and
// is not read here. Every file is streamed line by line through TextTable (file:line errors).
//
// Events: a ControlEvent{AckermannControl} per control row; an ObservationEvent per stamp of
// the associated file, bearing = angle_laser - pi/2 (left positive), landmark = feature_id;
// a GpsFix per GPS row. At equal stamps: observations, then the control, then GPS.
// Checks besides the table rules: time going backwards within a file, range <= 0, an angle
// outside [0, pi] (the laser's field of view), a negative feature id.
//
// Models: AckermannModel with victoriaParkGeometry(): as in Guivant and Nebot's published
// model, the state is the pose of the laser (a, b from the rear axle), so the range-bearing
// sensor sits at the state's origin and trajectory.tum is the laser's path. No ground
// truth; the start pose is the origin with heading 0, so errors are measured against GPS
// after a rigid alignment.
#include <seif/io/event_source.hpp>
#include <seif/models/ackermann_model.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace seif {

/// Wheelbase L = 2.83 m, encoder H = 0.76 m left of the centre line, state at the laser:
/// a = 3.78 m ahead of the rear axle and b = 0.50 m to the LEFT (the published model
/// x' = x + dt vc (cos phi - tan(alpha) (a sin phi + b cos phi) / L) is the velocity of the
/// point R(phi) (a, b) of a body turning at vc tan(alpha) / L).
AckermannGeometry victoriaParkGeometry();

/// A folder holding controls.txt and tree_observations_associated_UTS.txt.
bool looksLikeVictoriaPark(const std::filesystem::path& path);

/// Noise names: sigma_speed, sigma_steering (rate form by default), sigma_range,
/// sigma_bearing; defaults in victoria_park.cpp with their sources.
std::unique_ptr<EventSource> openVictoriaPark(const std::filesystem::path& dir, const DatasetOptions& options);

/// The files in memory (name -> content; an absent name is a missing file): for fuzzing.
struct VictoriaParkFiles {
  std::string folder;
  std::map<std::string, std::string, std::less<>> text;
};
std::unique_ptr<EventSource> openVictoriaPark(const VictoriaParkFiles& files, const DatasetOptions& options);

}  // namespace seif
