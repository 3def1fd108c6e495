#pragma once
// Option groups shared by the commands that run filters.
#include <seif/association/association.hpp>
#include <seif/filters/factory.hpp>
#include <seif/core/dataset.hpp>
#include <seif/io/event_source.hpp>

#include <map>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace seif::cli {

// Validators of flag values, applied to the value as typed before CLI11 converts it (CLI11
// alone lets nan through CLI::PositiveNumber, wraps `--seed -1` to 2^64-1, saturates seeds
// past 2^64 and reads 010 as octal). A bad value is a usage error (exit 1) whose message
// names the flag: "--sigma-v: must be finite and > 0, found nan".

/// The noise sigmas' rule (the same as meta.json's): a finite number > 0.
bool isPositiveFinite(double v);
/// A decimal number satisfying isPositiveFinite: the sigma flags and bench's budgets.
CLI::Validator positiveFinite();
/// A path that is not empty (an empty one would silently mean "not given").
CLI::Validator nonEmptyPath();
/// A decimal integer in [lo, hi] (no fraction, exponent, nan or inf), passed on to the
/// conversion in canonical form (so 010 is ten). Add it with Option::transform(): check()
/// would drop the canonical form.
CLI::Validator integerIn(long long lo, long long hi);
/// A comma-separated list of filter specs (splitFilterList, parseFilterSpec), checked before
/// any work; the message names the bad spec. A single spec passes it too.
CLI::Validator filterSpecs();
/// A seed: a decimal integer in [0, 2^64 - 1]; like integerIn, for Option::transform().
CLI::Validator seedValue();

/// --clutter and --detection-probability of the commands that simulate (WorldConfig's
/// clutter and detection_probability; docs/simulator.md "Clutter and missed detections").
void addDetectionFlags(CLI::App& cmd, double& clutter, double& detection_probability);

/// Checks a command's output folder before any work: empty is a usage error
/// (InvalidArgument); otherwise seif::requireWritableDirectory, which creates the
/// folder and throws DataError naming it when it is not a folder or not writable (exit 2).
void requireOutputFolder(const std::string& out);

/// --sigma-* flags of `seif run`: each overrides the dataset's noise value of that name
/// (the reader says which names its format takes; DatasetOptions::noise). Every sigma must
/// be finite and > 0 (isPositiveFinite): a bad flag is a usage error.
struct NoiseFlags {
  std::map<std::string, std::optional<double>> sigmas;  ///< noise name -> value if given
  std::string form;                                      ///< --noise-form, empty: the format's
  std::string isam_landmarks = "cartesian";              ///< --isam-landmarks
  std::string detections = "associated";                 ///< --detections
  void add(CLI::App& cmd);
  DatasetOptions resolve() const;
};

/// The filters' options as flags, one per row of the filter option table (filterOptions():
/// --linearization, --iterations, --active, --relax, --sparsify, ...; not the profile), with
/// the library's defaults. A spec's own keys (--filter seif:active=4) override them.
struct FilterFlags {
  std::map<std::string, std::string> values;  ///< option key -> value as typed
  /// Every option's flag; the batch's (--init, --solver) only with `batch`.
  void add(CLI::App& cmd, bool batch = false);
  /// The flags as a spec's defaults (name "seif").
  FilterSpec resolve() const;
  /// The flags given on the command line that `filter` (a spec) does not take: a SEIF
  /// option with ekf or eif, a batch option without batch or `smooth`.
  std::vector<std::string> ignoredBy(const std::string& filter, bool smooth) const;

 private:
  std::vector<std::pair<const FilterOption*, const CLI::Option*>> flags_;
};

/// Data association's flags, one per row of the association option table
/// (associationOptions(): --association, --gate-marginal, the gates, --confirm, --window,
/// --provisional, ...), shared by run and bench, with the library's defaults.
struct AssociationFlags {
  std::map<std::string, std::string> values;  ///< option key -> value as typed
  /// Without `tuning` only the rows that are not tuning (--association, --gate-marginal).
  void add(CLI::App& cmd, bool tuning = true);
  AssociationOptions resolve() const;
  /// With --association known: the flags given that only nn and jcbb read.
  std::vector<std::string> ignoredByKnown() const;

 private:
  std::vector<std::pair<std::string, const CLI::Option*>> flags_;
};

/// The keys a filter spec takes, for --filter's help (from filterOptions()).
std::string filterSpecHelp();

/// A progress bar on stderr when it is a terminal; silent otherwise.
class Progress {
 public:
  explicit Progress(std::string label);
  void operator()(std::size_t done, std::size_t total);
  void operator()(double fraction);
  ~Progress();

 private:
  std::string label_;
  bool tty_;
  bool drawn_ = false;
};

/// Runs scripts/figures/<script> with Debian's /usr/bin/python3 (which has matplotlib) on
/// `args`. Missing Python or matplotlib is not an error: prints how to render later.
/// Returns whether the script ran and succeeded.
bool renderFigure(const std::string& script, const std::vector<std::string>& args);


}  // namespace seif::cli
