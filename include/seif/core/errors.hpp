#pragma once
// Two tiers of errors (docs/conventions.md): programmer errors are asserts; everything a
// caller can cause throws one of these typed exceptions, all under seif::Error, each saying
// what went wrong and where. The CLI turns DataError and NumericError into one line and
// exit 2, InvalidArgument into exit 1; Python raises them as seif.Error subclasses.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace seif {

/// The base of every error seif throws: catch (const seif::Error&) catches them all.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Malformed input: names the file and line, formatted "file:line: what is wrong".
/// The message is printable whatever bytes the input held: control characters (NUL
/// included), DEL, C1 controls and bytes that are not valid UTF-8 appear as \xNN
/// (what() is a C string: a raw NUL would cut it). file() is the name as given.
class DataError : public Error {
 public:
  DataError(const std::string& file, long line, const std::string& what)
      : Error(format(file, line, what)), file_(file), line_(line) {}
  const std::string& file() const { return file_; }
  long line() const { return line_; }

 private:
  static std::string format(const std::string& file, long line, const std::string& what) {
    std::string msg = printable(file);
    if (line > 0) msg.append(":").append(std::to_string(line));
    msg.append(": ").append(printable(what));
    return msg;
  }

  /// Length of the valid UTF-8 sequence of two or more bytes starting at s[i] that is not a
  /// C1 control (U+0080..U+009F); 0 when there is none.
  static std::size_t multibyte(std::string_view s, std::size_t i) {
    const auto at = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char c = at(i);
    std::size_t n = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // range of the second byte
    if (c >= 0xC2 && c <= 0xDF) {
      n = 2;
      if (c == 0xC2) lo = 0xA0;
    } else if (c >= 0xE0 && c <= 0xEF) {
      n = 3;
      if (c == 0xE0) lo = 0xA0;
      if (c == 0xED) hi = 0x9F;  // no surrogates
    } else if (c >= 0xF0 && c <= 0xF4) {
      n = 4;
      if (c == 0xF0) lo = 0x90;
      if (c == 0xF4) hi = 0x8F;  // nothing above U+10FFFF
    } else {
      return 0;
    }
    if (s.size() - i < n || at(i + 1) < lo || at(i + 1) > hi) return 0;
    for (std::size_t k = 2; k < n; ++k) {
      if (at(i + k) < 0x80 || at(i + k) > 0xBF) return 0;
    }
    return n;
  }

  static std::string printable(std::string_view s) {
    constexpr char kHex[] = "0123456789abcdef";
    std::string out;
    out.reserve(s.size());
    for (std::size_t i = 0; i < s.size();) {
      const auto c = static_cast<unsigned char>(s[i]);
      if (c >= 0x20 && c < 0x7F) {
        std::size_t end = i + 1;
        while (end < s.size() && s[end] >= 0x20 && s[end] < 0x7F) ++end;
        out.append(s.substr(i, end - i));
        i = end;
      } else if (const std::size_t n = multibyte(s, i); n > 0) {
        out.append(s.substr(i, n));
        i += n;
      } else {
        out.append("\\x").append(1, kHex[c >> 4]).append(1, kHex[c & 0xF]);
        ++i;
      }
    }
    return out;
  }

  std::string file_;
  long line_;
};

/// A numerical failure inside a filter (singular innovation, indefinite information),
/// naming the filter, the step and the landmark when known.
class NumericError : public Error {
 public:
  using Error::Error;
};

/// A bad argument: an option out of range, an unknown name, a model asked the impossible
/// (a zero-range measurement inversion), an observation without a landmark id where the
/// filter needs known association. The message names the option or the observation.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

/// What a model or filter cannot do with the data it was given (inverting a zero range, an
/// observation without a landmark id where association is known): bad data more than a bad
/// option, so the CLI exits 2 for it.
class ModelError : public InvalidArgument {
 public:
  using InvalidArgument::InvalidArgument;
};

/// A run stopped on request (RunRequest::stop: Ctrl-C in `seif run`) before it had anything
/// to write. The CLI exits 130 for it, as for a run it stopped after writing its outputs.
class Interrupted : public Error {
 public:
  using Error::Error;
};

/// A landmark id that is not in the map.
class UnknownLandmark : public Error {
 public:
  UnknownLandmark(const std::string& filter, int id)
      : Error(filter + ": landmark " + std::to_string(id) + " is not in the map"), id_(id) {}
  int id() const { return id_; }

 private:
  int id_;
};

}  // namespace seif
