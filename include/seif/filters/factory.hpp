#pragma once
// Builds any of the filters by name: "ekf", "eif" or "seif".
#include <seif/filters/seif_slam.hpp>
#include <seif/filters/slam_filter.hpp>

#include <memory>
#include <string_view>

namespace seif {

/// Throws std::invalid_argument for an unknown name, listing the valid ones.
std::unique_ptr<SlamFilter> makeFilter(std::string_view name, const Pose2& start,
                                       const FilterConfig& config,
                                       const SeifOptions& seif_options = {});

}  // namespace seif
