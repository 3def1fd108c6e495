#pragma once
// Reader and writer of the UTIAS MRCLAM dataset layout (../shared/data/README.md):
//   Barcodes.dat               subject barcode
//   Landmark_Groundtruth.dat   subject x y x_sd y_sd
//   RobotN_Odometry.dat        time v w
//   RobotN_Measurement.dat     time barcode range bearing
//   RobotN_Groundtruth.dat     time x y theta      (optional)
//   meta.json                  {"noise": {...}}    (optional; written by `seif simulate`)
// Every field is checked; bad input throws DataError("file:line: what is wrong").
#include <seif/io/dataset.hpp>

#include <filesystem>

namespace seif {

/// Reads robot `robot` (1-5) of an MRCLAM folder. Measurements of robots and of unknown
/// barcodes are dropped and counted in RobotLog::dropped.
RobotLog readMrclam(const std::filesystem::path& dir, int robot = 1);

/// Writes `log` as robot `log.robot` of an MRCLAM folder (creating it), with barcodes
/// assigned to the landmark subjects, and meta.json when log.noise is set.
void writeMrclam(const std::filesystem::path& dir, const RobotLog& log);

}  // namespace seif
