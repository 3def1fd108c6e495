#include "filters/seif_slam.hpp"
#include <seif/core/errors.hpp>
#include "filters/batch_map.hpp"
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include <seif/filters/factory.hpp>

#include <charconv>
#include <stdexcept>
#include <string>

namespace seif {

namespace {

[[noreturn]] void badSpec(std::string_view text, const std::string& what) {
  throw InvalidArgument("filter '" + std::string(text) + "': " + what);
}

int parseInt(std::string_view text, std::string_view key, std::string_view value) {
  int v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size()) {
    badSpec(text, std::string(key) + "=" + std::string(value) + " is not an integer");
  }
  return v;
}

std::uint64_t parseSeed(std::string_view text, std::string_view value) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size()) {
    badSpec(text, "seed=" + std::string(value) + " is not an integer in [0, 2^64 - 1]");
  }
  return v;
}

}  // namespace

FilterSpec parseFilterSpec(std::string_view text, Linearization linearization, const SeifOptions& seif) {
  FilterSpec spec;
  spec.text = std::string(text);
  spec.linearization = linearization;
  spec.seif = seif;
  const std::size_t colon = text.find(':');
  spec.name = std::string(text.substr(0, colon));
  if (spec.name != "ekf" && spec.name != "eif" && spec.name != "seif" && spec.name != "batch") {
    badSpec(text, "unknown filter '" + spec.name + "' (expected ekf, eif, seif or batch)");
  }
  if (colon == std::string_view::npos) return spec;
  std::string_view rest = text.substr(colon + 1);
  if (rest.empty()) badSpec(text, "nothing after ':' (expected key=value,...)");
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    const std::size_t eq = item.find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == item.size()) {
      badSpec(text, "'" + std::string(item) + "' is not key=value");
    }
    const std::string_view key = item.substr(0, eq);
    const std::string_view value = item.substr(eq + 1);
    try {
      if (key == "linearization") {
        if (spec.name == "batch") badSpec(text, "the batch MAP relinearises at every iteration; it takes no linearization");
        spec.linearization = parseLinearization(value);
        continue;
      }
      if (spec.name != "seif") badSpec(text, "unknown option '" + std::string(key) + "' for " + spec.name);
      if (key == "sparsify") spec.seif.sparsify = SeifOptions::parseSparsify(value);
      else if (key == "active") spec.seif.max_active = parseInt(text, key, value);
      else if (key == "beta") spec.seif.eseif_beta = parseInt(text, key, value);
      else if (key == "relax") spec.seif.relax = parseInt(text, key, value);
      else if (key == "mean") spec.seif.mean = SeifOptions::parseMean(value);
      else if (key == "deactivate") spec.seif.deactivate = SeifOptions::parseDeactivate(value);
      else if (key == "recovery") spec.seif.recovery = SeifOptions::parseRecovery(value);
      else if (key == "relax-order") spec.seif.relax_order = SeifOptions::parseRelaxOrder(value);
      else if (key == "covariance") spec.seif.covariance = SeifOptions::parseCovariance(value);
      else if (key == "seed") spec.seif.seed = parseSeed(text, value);
      else {
        badSpec(text, "unknown option '" + std::string(key) +
                          "' (seif takes linearization, sparsify, beta, active, relax, mean, deactivate, "
                          "recovery, relax-order, covariance, seed)");
      }
    } catch (const InvalidArgument& e) {
      const std::string what = e.what();
      if (what.rfind("filter '", 0) == 0) throw;
      badSpec(text, what);
    }
  }
  return spec;
}

std::vector<std::string> splitFilterList(std::string_view list) {
  std::vector<std::string> specs;
  while (true) {
    const std::size_t comma = list.find(',');
    const std::string_view item = list.substr(0, comma);
    if (item.empty()) throw InvalidArgument("filter list '" + std::string(list) + "': an empty item");
    const bool option = item.find('=') != std::string_view::npos && item.find(':') == std::string_view::npos;
    if (option) {
      if (specs.empty()) throw InvalidArgument("filter list: option '" + std::string(item) + "' before any filter");
      specs.back().append(",").append(item);
    } else {
      specs.emplace_back(item);
    }
    if (comma == std::string_view::npos) break;
    list = list.substr(comma + 1);
  }
  return specs;
}

std::unique_ptr<SlamFilter> makeFilter(const FilterSpec& spec, const Pose2& start, const FilterConfig& config) {
  FilterConfig c = config;
  c.linearization = spec.linearization;
  if (spec.name == "ekf") return std::make_unique<EkfSlam>(start, c);
  if (spec.name == "eif") return std::make_unique<EifSlam>(start, c);
  if (spec.name == "seif") return std::make_unique<SeifSlam>(start, c, spec.seif);
  if (spec.name == "batch") return std::make_unique<BatchMap>(start, c);
  throw InvalidArgument("unknown filter '" + spec.name + "' (expected ekf, eif, seif or batch)");
}

std::unique_ptr<SlamFilter> makeFilter(std::string_view spec, const Pose2& start,
                                       const FilterConfig& config, const SeifOptions& seif_options) {
  return makeFilter(parseFilterSpec(spec, config.linearization, seif_options), start, config);
}

}  // namespace seif
