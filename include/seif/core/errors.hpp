#pragma once
// Two tiers of errors (docs/conventions.md): programmer errors are asserts; bad data
// throws one of these typed exceptions, which the CLI turns into one line and exit 2.
#include <stdexcept>
#include <string>

namespace seif {

/// Malformed input: names the file and line, formatted "file:line: what is wrong".
class DataError : public std::runtime_error {
 public:
  DataError(const std::string& file, long line, const std::string& what)
      : std::runtime_error(format(file, line, what)), file_(file), line_(line) {}
  const std::string& file() const { return file_; }
  long line() const { return line_; }

 private:
  static std::string format(const std::string& file, long line, const std::string& what) {
    std::string msg = file;
    if (line > 0) msg.append(":").append(std::to_string(line));
    msg.append(": ").append(what);
    return msg;
  }
  std::string file_;
  long line_;
};

/// A numerical failure inside a filter (singular innovation, indefinite information),
/// naming the step and the landmark when known.
class NumericError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An invalid argument to a model or a filter (e.g. a zero-range measurement inversion).
class ModelError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

}  // namespace seif
