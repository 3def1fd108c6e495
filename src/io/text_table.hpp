#pragma once
// The strict parser of whitespace-separated text tables that every reader shares
// (MRCLAM, Victoria Park, iSAM, g2o). Rules, the same for every format:
// - a line whose first non-blank character is '#' and a blank line are skipped;
// - fields are separated by spaces, tabs, '\v', '\f' (a trailing '\r' is ignored);
// - line numbers count every line from 1, comments included;
// - numbers must parse completely (std::from_chars) and be finite; integers must be integers.
// Every failure is a DataError "file:line: what", naming the column when there is one.
//
// A table reads either text held in memory (fuzzing, tests) or a file in chunks, so a
// reader's memory does not grow with the file.
#include <seif/core/errors.hpp>
#include "core/files.hpp"

#include <array>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace seif {

/// The largest range a reader takes, in metres: beyond it a value is corrupt (its landmark
/// would be placed, and its information computed, out of all proportion).
inline constexpr double kMaxRange = 1e6;
/// The largest speed [m/s] and turn rate [rad/s] a reader takes: no vehicle a landmark log
/// comes from is faster; beyond them a control is corrupt, and the step it drives fails.
inline constexpr double kMaxSpeed = 1e3;
inline constexpr double kMaxTurnRate = 1e3;

class TextTable {
 public:
  /// Most fields a line may have (g2o's EDGE_SE2 has 12).
  static constexpr std::size_t kMaxFields = 16;

  /// A table over `text` (which must outlive it); `name` names it in messages.
  TextTable(std::string name, std::string_view text);
  /// A table over the file at `path`, read in chunks. Throws DataError naming the file when
  /// it is missing, not a regular file, a symbolic-link loop or unreadable.
  static TextTable open(const std::filesystem::path& path);

  TextTable(TextTable&&) noexcept;
  TextTable& operator=(TextTable&&) noexcept;
  ~TextTable();

  /// Advances to the next data line; false at the end of the input.
  bool next();

  const std::string& name() const { return name_; }
  /// Bytes read so far (for progress bars).
  std::size_t offset() const;
  long line() const { return line_; }
  /// Fields of the current line.
  std::size_t size() const { return count_; }
  std::string_view field(std::size_t col) const { return fields_[col]; }

  /// Names the columns of the current line (for messages) and checks their number.
  /// `what` names the record in the message ("expected 4 fields (time v w x) in ODOMETRY").
  void expect(std::initializer_list<const char*> columns, std::string_view what = {});

  /// Column `col` (0-based) as a finite double / an int / a non-negative long long.
  double real(std::size_t col) const;
  /// real(), an angle in radians within one turn either way (|a| <= 2 pi, to the printed
  /// precision): a bearing or a heading increment beyond that is not one.
  double angle(std::size_t col) const;
  /// real(), a sensor's range in metres: > 0 and at most kMaxRange.
  double range(std::size_t col) const;
  /// real(), a position or a displacement in metres: at most kMaxRange either way.
  double coordinate(std::size_t col) const;
  int integer(std::size_t col) const;
  long long index(std::size_t col) const;
  /// Half a unit of the last printed decimal of column `col` as written ("3.141593":
  /// 5e-7, "12": 0.5, "1.5e-3": 5e-5): the precision the file gives the value.
  double halfUnit(std::size_t col) const;

  [[noreturn]] void fail(const std::string& what) const;
  /// "column 3 (range)", or "column 3" when the columns have no names.
  std::string columnName(std::size_t col) const;

 private:
  bool split(std::string_view line);

  std::string name_;
  std::string_view text_;  // memory mode
  std::size_t pos_ = 0;
  std::unique_ptr<std::ifstream> file_;  // file mode
  std::string buffer_;                   // the current line in file mode
  std::size_t consumed_ = 0;             // bytes read in file mode
  long line_ = 0;
  std::size_t count_ = 0;
  std::array<std::string_view, kMaxFields> fields_{};
  std::array<const char*, kMaxFields> columns_{};
  std::size_t named_ = 0;
};

/// Time stamps of one file must not decrease (equal stamps are fine).
class TimeOrder {
 public:
  void check(const TextTable& table, double time);

 private:
  double previous_ = -std::numeric_limits<double>::infinity();
  long previous_line_ = 0;
};

/// Shortest decimal form that reads back bit-identical (std::to_chars).
std::string formatDouble(double x);

/// A field as shown in a message: quoted, and shortened if absurdly long.
std::string quotedField(std::string_view field);

}  // namespace seif
