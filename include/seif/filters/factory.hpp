#pragma once
// Builds any filter from its spec: a name ("ekf", "eif", "seif", "batch") and options,
// "seif:sparsify=eseif,linearization=fej" (the form `--filter` and `--filters` take).
#include <seif/filters/batch_options.hpp>
#include <seif/filters/seif_options.hpp>
#include <seif/filters/slam_filter.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace seif {

/// A filter name with the options its spec set; everything else from the defaults given.
struct FilterSpec {
  std::string text;  ///< the spec as written, e.g. "seif:linearization=fej"
  std::string name;  ///< ekf | eif | seif | batch
  Linearization linearization = Linearization::Standard;
  int iterations = 1;  ///< FilterConfig::iterations
  SeifOptions seif;
  BatchOptions batch;
};

/// One option of the filters. The table of them (filterOptions()) is the single description
/// the spec parser, the CLI's flags (`--<key>`), metrics.json ("filter_spec" and the "seif"
/// object) and Python's names (the key with '_' for '-') all come from.
struct FilterOption {
  enum class Scope { AllButBatch, Seif, Batch };  ///< which filters take it
  /// Length: a finite number >= 0 [m]. Real: a finite number strictly between min and max.
  /// Profile: a spec-only shorthand that sets other options (the keys after it in the spec
  /// override it); the canonical spec, the flags and metrics.json list the options it set,
  /// not it.
  enum class Kind { Choice, Integer, Seed, Length, Fraction, Real, Profile };
  std::string_view key;      ///< e.g. "relax-order"
  Scope scope;
  Kind kind;
  std::string_view choices;  ///< Choice: the values, "cyclic|random"
  std::int64_t min = 0;      ///< Integer: the range
  std::int64_t max = 0;
  std::string_view help;
  /// Sets the option in a spec from its text; throws InvalidArgument naming key and value.
  void (*set)(FilterSpec& spec, std::string_view value);
  /// The option's value in a spec, as text set() takes.
  std::string (*get)(const FilterSpec& spec);
};

/// Every filter option, in the order the canonical spec lists them.
std::span<const FilterOption> filterOptions();

/// Whether filter `name` (ekf | eif | seif | batch) takes the option.
bool takesOption(std::string_view name, const FilterOption& option);

/// profile=consistent, the recommended constant-time configuration (README, "Consistent in
/// constant time"): linearization=invariant, iterations=3, active=30, motion=deferred, the
/// amortised mean with its coarse level (coarse=rigid) relaxing 40 landmarks a step,
/// over-relaxed (omega=1.95) in the wildfire order (relax-order=wildfire: first where the
/// mean moved), and the sparsification that claims nothing on the free directions
/// (gauge=kept). With
/// sparsify=conservative add gauge=paper (the two do not combine).
inline constexpr std::string_view kConsistentProfile =
    "linearization=invariant,iterations=3,active=30,motion=deferred,coarse=rigid,relax=40,omega=1.95,relax-order=wildfire,gauge=kept";

/// "name:key=value,..." with every option the filter takes, in table order: the exact
/// configuration a spec ran with, as metrics.json records it; parses back to an equal spec.
std::string canonicalFilterSpec(const FilterSpec& spec);

/// Parses "name[:key=value,...]" with the keys of filterOptions() (linearization for every
/// filter but the batch; the SEIF's options for the SEIF). Unset keys keep `linearization`
/// and `seif`. Throws InvalidArgument naming the spec and what is wrong (unknown name, key
/// or value, a value out of range, a key the filter does not take).
FilterSpec parseFilterSpec(std::string_view text, Linearization linearization = Linearization::Standard,
                           const SeifOptions& seif = {});
/// The same with every unset option from `defaults` (its name and text ignored).
FilterSpec parseFilterSpec(std::string_view text, const FilterSpec& defaults);

/// Splits a comma-separated list of specs, "batch,ekf,seif:sparsify=eseif,beta=4": an item
/// with '=' but no ':' continues the previous spec's options. Throws InvalidArgument
/// for an empty item or options before any filter name.
std::vector<std::string> splitFilterList(std::string_view list);

/// Throws InvalidArgument for an unknown name, listing the valid ones.
std::unique_ptr<SlamFilter> makeFilter(const FilterSpec& spec, const Pose2& start, const FilterConfig& config);

/// The batch MAP smoother after `filter` (`seif run --smooth`): the filter runs alongside it
/// (its outlier gate is the smoother's), gives the estimates while streaming, and its final
/// trajectory and map start the smoother's solve at finish(). smootherReport()->init names it.
std::unique_ptr<SlamFilter> makeSmoother(const FilterSpec& filter, const Pose2& start, const FilterConfig& config,
                                         const BatchOptions& options = {});
/// The filter a smoother made by makeSmoother() runs alongside (null for any other filter).
const SlamFilter* smoothedFilter(const SlamFilter& smoother);

/// makeFilter(parseFilterSpec(spec, config.linearization, seif_options), start, config).
std::unique_ptr<SlamFilter> makeFilter(std::string_view spec, const Pose2& start,
                                       const FilterConfig& config,
                                       const SeifOptions& seif_options = {});

}  // namespace seif
