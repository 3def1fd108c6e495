#pragma once
// The text of an option's value, as a spec key or a flag gives it, parsed and printed back:
// shared by the option tables (filterOptions() in factory.cpp, associationOptions() in
// association/options.cpp). Each parser throws InvalidArgument naming key and value.
#include <cstdint>
#include <string>
#include <string_view>

namespace seif::options {

std::int64_t parseInteger(std::string_view key, std::string_view value, std::int64_t lo, std::int64_t hi);
/// A finite number in [lo, hi) (hi_open) or [lo, hi].
double parseReal(std::string_view key, std::string_view value, double lo, double hi, bool hi_open);
/// A finite number >= 0 [m].
double parseLength(std::string_view key, std::string_view value);
/// A finite number in the open interval (lo, hi).
double parseBetween(std::string_view key, std::string_view value, double lo, double hi);
/// A fraction in [0, 1).
double parseFraction(std::string_view key, std::string_view value);
std::uint64_t parseSeed(std::string_view value);
/// "true" | "false".
bool parseBool(std::string_view key, std::string_view value);
/// Shortest text that parses back to v.
std::string formatReal(double v);

}  // namespace seif::options
