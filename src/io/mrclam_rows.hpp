#pragma once
// The rows of the MRCLAM files, parsed with every check: shared by readMrclam (whole files)
// and the streaming MRCLAM source (line by line). Internal to src/io.
#include <seif/core/dataset.hpp>
#include "io/text_table.hpp"

#include <map>
#include <optional>

namespace seif {

using Barcodes = std::map<int, int>;  ///< barcode -> subject

Barcodes parseBarcodes(TextTable& table);            ///< all of Barcodes.dat
std::map<int, Vec2> parseLandmarks(TextTable& table);  ///< all of Landmark_Groundtruth.dat
/// The current row of RobotN_Odometry.dat / _Measurement.dat / _Groundtruth.dat. A
/// measurement of a robot or of an unknown barcode is counted in `dropped`, not returned.
OdometryRecord odometryRow(TextTable& table, TimeOrder& order);
std::optional<MeasurementRecord> measurementRow(TextTable& table, TimeOrder& order, const Barcodes& barcodes,
                                                DropCounts& dropped);
TimedPose groundtruthRow(TextTable& table, TimeOrder& order);

}  // namespace seif
