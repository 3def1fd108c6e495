#pragma once
// Shared by the fuzz targets and the regression test (tests/test_io_mrclam.cpp): the input
// format of fuzz_mrclam and the properties every result must have.
//
// fuzz_mrclam input: the files of robot 1 in the order of kMrclamFiles, separated by the
// line "%%" (kSeparator); the last section takes the rest of the input. Sections that are
// not there are missing files.
#include <seif/io/mrclam.hpp>

#include <cmath>
#include <cstddef>
#include <iterator>
#include <string>
#include <string_view>

namespace seif::fuzz {

inline constexpr std::string_view kSeparator = "\n%%\n";
inline constexpr const char* kMrclamFiles[] = {"Barcodes.dat",        "Landmark_Groundtruth.dat",
                                               "Robot1_Odometry.dat", "Robot1_Measurement.dat",
                                               "Robot1_Groundtruth.dat", "meta.json"};
inline constexpr int kRobot = 1;
inline constexpr const char* kFolder = "fuzz";

inline MrclamFiles splitMrclamInput(std::string_view input) {
  MrclamFiles files;
  files.folder = kFolder;
  constexpr std::size_t kCount = std::size(kMrclamFiles);
  for (std::size_t i = 0; i < kCount; ++i) {
    const std::size_t end = (i + 1 == kCount) ? std::string_view::npos : input.find(kSeparator);
    files.text.emplace(kMrclamFiles[i], input.substr(0, end));
    if (end == std::string_view::npos) break;
    input.remove_prefix(end + kSeparator.size());
  }
  return files;
}

/// No control character or DEL (DataError escapes them).
inline bool isPrintable(std::string_view message) {
  for (const char c : message) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x20 || b == 0x7F) return false;
  }
  return true;
}

inline bool isValidNoise(const NoiseModel& n) {
  for (const double s : {n.sigma_v, n.sigma_w, n.sigma_range, n.sigma_bearing}) {
    if (!std::isfinite(s) || !(s > 0.0)) return false;
  }
  return true;
}

/// The first property of a log the reader accepted that does not hold; empty when all hold.
inline std::string brokenInvariant(const RobotLog& log) {
  for (std::size_t i = 0; i < log.odometry.size(); ++i) {
    const OdometryRecord& r = log.odometry[i];
    if (!std::isfinite(r.time) || !std::isfinite(r.v) || !std::isfinite(r.w)) {
      return "non-finite odometry";
    }
    if (i > 0 && r.time < log.odometry[i - 1].time) return "odometry time goes backwards";
  }
  for (std::size_t i = 0; i < log.measurements.size(); ++i) {
    const MeasurementRecord& m = log.measurements[i];
    if (!std::isfinite(m.time) || !std::isfinite(m.bearing)) return "non-finite measurement";
    if (!(m.range > 0.0) || !std::isfinite(m.range)) return "range not finite and > 0";
    // a robot's subject is never kept; kClutterSubject (0) is a false detection, kept
    if (m.subject <= 5 && m.subject != kClutterSubject) return "measurement of a robot kept";
    if (i > 0 && m.time < log.measurements[i - 1].time) return "measurement time goes backwards";
  }
  for (std::size_t i = 0; i < log.groundtruth.size(); ++i) {
    if (!std::isfinite(log.groundtruth[i].time) || !log.groundtruth[i].pose.allFinite()) {
      return "non-finite ground truth";
    }
    if (i > 0 && log.groundtruth[i].time < log.groundtruth[i - 1].time) {
      return "ground truth goes backwards";
    }
  }
  for (const auto& [subject, p] : log.landmarks) {
    if (subject <= 5 || !p.allFinite()) return "bad landmark";
  }
  if (log.noise && !isValidNoise(*log.noise)) return "noise sigma not finite and > 0";
  return {};
}

}  // namespace seif::fuzz
