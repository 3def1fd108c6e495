#pragma once
// Builds any filter from its spec: a name ("ekf", "eif", "seif", "batch") and options,
// "seif:sparsify=eseif,linearization=fej" (the form `--filter` and `--filters` take).
#include <seif/filters/seif_options.hpp>
#include <seif/filters/slam_filter.hpp>

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace seif {

/// A filter name with the options its spec set; everything else from the defaults given.
struct FilterSpec {
  std::string text;  ///< the spec as written, e.g. "seif:linearization=fej"
  std::string name;  ///< ekf | eif | seif | batch
  Linearization linearization = Linearization::Standard;
  SeifOptions seif;
};

/// Parses "name[:key=value,...]". Keys: linearization=standard|fej (every filter but the
/// batch); for the SEIF sparsify=seif|eseif, beta=B (eseif), active=N, relax=K, mean=amortized|exact,
/// deactivate=weakest|oldest, recovery=before-update|after-update, relax-order=cyclic|random,
/// covariance=exact|local, seed=S. Unset keys keep `linearization` and `seif`. Throws InvalidArgument naming
/// the spec and what is wrong (unknown name, key or value; a key the filter does not take).
FilterSpec parseFilterSpec(std::string_view text, Linearization linearization = Linearization::Standard,
                           const SeifOptions& seif = {});

/// Splits a comma-separated list of specs, "batch,ekf,seif:sparsify=eseif,beta=4": an item
/// with '=' but no ':' continues the previous spec's options. Throws InvalidArgument
/// for an empty item or options before any filter name.
std::vector<std::string> splitFilterList(std::string_view list);

/// Throws InvalidArgument for an unknown name, listing the valid ones.
std::unique_ptr<SlamFilter> makeFilter(const FilterSpec& spec, const Pose2& start, const FilterConfig& config);

/// makeFilter(parseFilterSpec(spec, config.linearization, seif_options), start, config).
std::unique_ptr<SlamFilter> makeFilter(std::string_view spec, const Pose2& start,
                                       const FilterConfig& config,
                                       const SeifOptions& seif_options = {});

}  // namespace seif
