// Option values as text (src/filters/option_values.hpp).
#include "filters/option_values.hpp"

#include <seif/core/errors.hpp>

#include <charconv>
#include <cmath>

namespace seif::options {

namespace {

[[noreturn]] void bad(std::string_view key, std::string_view value, const std::string& what) {
  throw InvalidArgument(std::string(key) + "=" + std::string(value) + " " + what);
}

double finiteNumber(std::string_view key, std::string_view value) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size() || !std::isfinite(v)) bad(key, value, "is not a finite number");
  return v;
}

}  // namespace

std::int64_t parseInteger(std::string_view key, std::string_view value, std::int64_t lo, std::int64_t hi) {
  std::int64_t v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (end != value.data() + value.size() || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
    bad(key, value, "is not an integer");
  }
  if (ec == std::errc::result_out_of_range || v < lo || v > hi) {
    std::string what = "is outside [";  // built by appends: GCC 12's -Wrestrict misfires on "lit" + string&&
    bad(key, value, what.append(std::to_string(lo)).append(", ").append(std::to_string(hi)).append("]"));
  }
  return v;
}

double parseReal(std::string_view key, std::string_view value, double lo, double hi, bool hi_open) {
  const double v = finiteNumber(key, value);
  if (v < lo || v > hi || (hi_open && v == hi)) {
    bad(key, value, "is outside [" + formatReal(lo) + ", " + formatReal(hi) + (hi_open ? ")" : "]"));
  }
  return v;
}

double parseLength(std::string_view key, std::string_view value) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size() || !std::isfinite(v) || v < 0.0) {
    bad(key, value, "is not a finite length >= 0");
  }
  return v;
}

double parseBetween(std::string_view key, std::string_view value, double lo, double hi) {
  const double v = finiteNumber(key, value);
  if (!(v > lo && v < hi)) bad(key, value, "is outside (" + formatReal(lo) + ", " + formatReal(hi) + ")");
  return v;
}

double parseFraction(std::string_view key, std::string_view value) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size() || !(v >= 0.0 && v < 1.0)) {
    bad(key, value, "is not a fraction in [0, 1)");
  }
  return v;
}

std::uint64_t parseSeed(std::string_view value) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size()) {
    throw InvalidArgument("seed=" + std::string(value) + " is not an integer in [0, 2^64 - 1]");
  }
  return v;
}

bool parseBool(std::string_view key, std::string_view value) {
  if (value == "true") return true;
  if (value == "false") return false;
  bad(key, value, "is not true or false");
}

std::string formatReal(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, ec == std::errc() ? end : buf);
}

}  // namespace seif::options
