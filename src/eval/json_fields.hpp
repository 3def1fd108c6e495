#pragma once
// The JSON form of the settings and statistics the experiments' outputs repeat
// (metrics.json, results.json, bench.json): one spelling of each key. Private to the library.
#include "filters/seif_slam.hpp"
#include <seif/association/association.hpp>
#include <seif/filters/factory.hpp>
#include <seif/filters/slam_filter.hpp>

#include <nlohmann/json.hpp>

#include <cmath>

namespace seif {

nlohmann::json toJson(const NoiseModel& noise);
nlohmann::json toJson(const SeifOptions& options);
/// Every row of associationOptions(), by attribute.
nlohmann::json toJson(const AssociationOptions& options);
nlohmann::json toJson(const FilterStats& stats);

/// A finite number, or null (JSON has no NaN).
inline nlohmann::json finiteOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace seif
