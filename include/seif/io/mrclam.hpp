#pragma once
// Reader and writer of the UTIAS MRCLAM dataset layout (../shared/data/README.md):
//   Barcodes.dat               subject barcode
//   Landmark_Groundtruth.dat   subject x y x_sd y_sd
//   RobotN_Odometry.dat        time v w
//   RobotN_Measurement.dat     time barcode range bearing
//   RobotN_Groundtruth.dat     time x y theta      (optional)
//   meta.json                  {"noise": {...}}    (optional; written by `seif simulate`)
// Every field is checked; bad input throws DataError("file:line: what is wrong").
//
// Text files: lines whose first non-blank character is '#' and blank lines are skipped;
// fields are separated by spaces and tabs (a trailing '\r' is ignored); line numbers count
// every line from 1, comments included. Each data line must have exactly the listed fields;
// numbers must be finite and parse completely (std::from_chars), integers must be integers.
// Also rejected: time going backwards within a file (equal stamps are fine), range <= 0,
// a negative standard deviation, a barcode or subject listed twice in Barcodes.dat, a
// landmark listed twice or with a robot subject (1-5) in Landmark_Groundtruth.dat.
//
// Clutter: subject 0 (kClutterSubject, core/dataset.hpp) in Barcodes.dat names the barcode of
// false detections, which seif's simulator writes with clutter configured (the UTIAS data
// have no subject 0). Its measurements are read with subject 0 and become observations of
// no landmark (observationOf); subject 0 is never a landmark in Landmark_Groundtruth.dat.
//
// meta.json: {"format": "seif-mrclam", "robot": N, "noise": {"sigma_v": .., "sigma_w": ..,
// "sigma_range": .., "sigma_bearing": ..}}. Every key is optional; when "noise" is present
// all four sigmas must be finite numbers > 0 (the writer refuses to write others). "robot",
// when present, must be 1..5 (it is not required to match the robot being read: the noise
// of a simulated folder is shared). A malformed meta.json (a number beyond double range
// included) is a DataError naming the file (no line number).
//
// Files: a missing optional file (or a dangling symbolic link) is skipped; a symbolic-link
// loop, a folder or an unreadable file is a DataError naming the file.
#include <seif/core/dataset.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace seif {

/// Reads robot `robot` (1-5) of an MRCLAM folder. Measurements of robots and of unknown
/// barcodes are dropped and counted in RobotLog::dropped.
///
/// A measurement is kept when its barcode maps (Barcodes.dat) to a subject that is not a
/// robot; RobotLog::landmarks holds the positions of Landmark_Groundtruth.dat (x_sd and
/// y_sd are checked, then discarded). RobotLog::source is `dir`. Measurements before the
/// first odometry row are kept here; buildDataset() drops and counts them.
/// Throws DataError: robot outside 1..5 (naming `dir`), a missing or unreadable required
/// file (naming the file, no line), or any malformed line (naming file and line).
RobotLog readMrclam(const std::filesystem::path& dir, int robot = 1);

/// The files of an MRCLAM folder held in memory.
struct MrclamFiles {
  std::string folder;  ///< names the files in messages, as folder/NAME, and RobotLog::source
  /// File name ("Barcodes.dat", "Robot1_Odometry.dat", "meta.json", ...) -> content; a name
  /// that is absent is a missing file.
  std::map<std::string, std::string, std::less<>> text;
};

/// readMrclam(dir, robot) on files held in memory, with the same checks and messages
/// (files named as in the folder `files.folder`).
RobotLog readMrclam(const MrclamFiles& files, int robot = 1);

/// Parses the content of a meta.json (rules above): its noise, nullopt when it has none.
/// Throws DataError naming `name_for_errors`.
std::optional<NoiseModel> readMetaJson(std::string_view text, const std::string& name_for_errors);

/// Writes `log` as robot `log.robot` of an MRCLAM folder (creating it), with barcodes
/// assigned to the landmark subjects, and meta.json when log.noise is set.
///
/// Barcodes: subject s (robots 1-5 and every landmark subject of log.landmarks and
/// log.measurements, and clutter's subject 0 when a measurement has it) gets barcode 100 + s. Doubles are written in the shortest form that
/// reads back bit-identical, so readMrclam(dir, log.robot) returns `log` again (except
/// `source`, which becomes `dir`, and `dropped`, which is not stored). The folder-level files
/// (Barcodes.dat, Landmark_Groundtruth.dat, meta.json) are overwritten; an existing
/// RobotN_Groundtruth.dat is removed when log.groundtruth is empty; an existing meta.json
/// is left alone when log.noise is empty.
/// Throws DataError, before writing anything, when the log could not be read back: robot
/// outside 1..5, a landmark subject <= 5, a non-finite value, range <= 0, time going
/// backwards (naming the file and the line the row would have), a noise sigma that is not
/// finite and > 0 (naming meta.json and the key); or when a file cannot be written. Each file
/// is written atomically (writeFileAtomically): complete or, when writing fails, the old one.
void writeMrclam(const std::filesystem::path& dir, const RobotLog& log);

}  // namespace seif
