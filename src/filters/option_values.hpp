#pragma once
// The text of an option's value, as a spec key or a flag gives it, parsed and printed back:
// shared by the option tables (filterOptions() in factory.cpp, associationOptions() in
// association/options.cpp). Each parser throws InvalidArgument naming key and value.
#include <seif/core/errors.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace seif {
struct FilterConfig;
struct SeifOptions;

/// checkValues() (below) over the filter options' table (factory.cpp): the options filter
/// `name` (ekf | eif | seif) takes, from its config and, for the SEIF, its options. Each
/// filter's constructor runs it.
void checkFilterOptions(std::string_view name, const FilterConfig& config, const SeifOptions* seif = nullptr);

struct AssociationOptions;
/// checkValues() over the association options' table (association/options.cpp): what the
/// Associator's constructor runs.
void checkAssociationOptions(const AssociationOptions& values);
}  // namespace seif

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

/// The table's entry for `key` (an option table: an array of entries with `key`, `min`, `max`,
/// `set` and `get`). Each option's range is written once, in its entry.
template <typename Table>
const auto& entry(const Table& table, std::string_view key) {
  for (const auto& o : table) {
    if (o.key == key) return o;
  }
  throw std::logic_error("no option '" + std::string(key) + "' in its table");
}
/// parseInteger() over the range [min, max] of the table's entry for `key`.
template <typename Table>
std::int64_t parseIntegerOf(const Table& table, std::string_view key, std::string_view value) {
  const auto& o = entry(table, key);
  return parseInteger(key, value, o.min, o.max);
}
/// parseBetween() over the open range (min, max) of the table's entry for `key`.
template <typename Table>
double parseBetweenOf(const Table& table, std::string_view key, std::string_view value) {
  const auto& o = entry(table, key);
  return parseBetween(key, value, static_cast<double>(o.min), static_cast<double>(o.max));
}

/// Refuses option values the table's parsers would refuse: each selected option is printed
/// (get) and parsed back (set, on a copy), so a struct filled in C++ or Python is held to the
/// same ranges, in the same words, as a spec or a flag. Throws InvalidArgument("<what>: " +
/// the parser's message).
template <typename Table, typename Values, typename Select>
void checkValues(std::string_view what, const Table& table, const Values& values, Select select) {
  Values probe = values;
  for (const auto& o : table) {
    if (!select(o)) continue;
    try {
      o.set(probe, o.get(values));
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(std::string(what) + ": " + e.what());
    }
  }
}

}  // namespace seif::options
