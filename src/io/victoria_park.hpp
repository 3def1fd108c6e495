#pragma once
// Reader of the Victoria Park folder (Guivant & Nebot 2001; ../shared/data/README.md):
//   controls.txt                          time speed steering    (40 Hz; rear-left encoder, front wheels)
//   tree_observations_associated_UTS.txt  time range angle_laser feature_id x_est y_est
//                                         (known association, Huang et al.; x_est, y_est unused)
//   tree_detections.txt                   time scan_index range angle_laser diameter
//                                         (the raw detector output, no association; scan_index, diameter unused)
//   gps.txt                               time x y               (optional; failing unit: gaps, jumps)
// DatasetOptions::detections picks the detections: Associated (default) reads the UTS file,
// Raw reads tree_detections.txt (then the UTS file is optional). Every file is streamed line
// by line through TextTable (file:line errors).
//
// Events: a ControlEvent{AckermannControl} per control row; an ObservationEvent per stamp of
// the detections file, bearing = angle_laser - pi/2 (left positive); a GpsFix per GPS row.
// At equal stamps: observations, then the control, then GPS.
// Associated: landmark = truth = feature_id. Raw: landmark = kUnknownLandmark, truth = the
// feature id of the UTS row that is the same detection (same stamp: both files carry the
// laser scan's; range and angle equal within what both print), else kUnknownLandmark. Only
// the UTS rows of the current stamp are held. On the real folder every UTS row is one raw
// detection (46860 of 52974, 88.5 %, get a truth id); UTS rows no detection matches are
// counted in dropped() ("associated_rows_without_raw_detection").
// Checks besides the table rules: time going backwards within a file, range <= 0, an angle
// outside [0, pi] (the laser's field of view) by more than its printed precision (half a unit
// of its last decimal: 3.141593 is pi, clamped into [0, pi]), a negative feature id, scan
// index or diameter, and a scan index that is not one per stamp, increasing (scan_index and
// diameter are otherwise unused).
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

/// A folder holding controls.txt and tree_observations_associated_UTS.txt or tree_detections.txt.
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
