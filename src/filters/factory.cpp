#include "filters/seif_slam.hpp"
#include <seif/core/errors.hpp>
#include "filters/batch_map.hpp"
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include <seif/filters/factory.hpp>

#include "filters/information_ops.hpp"
#include "filters/option_values.hpp"

#include <algorithm>
#include <vector>
#include <array>
#include <limits>
#include <string>

namespace seif {

namespace {

[[noreturn]] void badSpec(std::string_view text, const std::string& what) {
  throw InvalidArgument("filter '" + std::string(text) + "': " + what);
}

using options::formatReal;
using options::parseBool;
using options::parseBetweenOf;
using options::parseIntegerOf;
using options::parseLength;
using options::parseFraction;
using options::parseSeed;

using Opt = FilterOption;
constexpr auto kAll = Opt::Scope::AllButBatch;
constexpr auto kSeif = Opt::Scope::Seif;
constexpr auto kChoice = Opt::Kind::Choice;
constexpr auto kInteger = Opt::Kind::Integer;
constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();

// The SEIF's documentation of each option is SeifOptions' (seif_options.hpp); the help
// here is the one line a flag or a spec error shows.
void applyProfile(FilterSpec& s, std::string_view v);

// Initialised before kOptions (declaration order within this file), which views it.
const std::string kProfileHelp = "a recommended configuration: consistent = " + std::string(kConsistentProfile) +
                                 " (honest covariances in constant time; README)";

const std::array<FilterOption, 25> kOptions = {{
    {"profile", kSeif, Opt::Kind::Profile, "consistent", 0, 0, kProfileHelp,
     &applyProfile, [](const FilterSpec&) { return std::string(); }},
    {"linearization", kAll, kChoice, "standard|fej|invariant|oc", 0, 0,
     "the Jacobians: at the newest estimates, at the first ones (FEJ), the right-invariant EKF's, "
     "or the observability-constrained EKF's (oc)",
     [](FilterSpec& s, std::string_view v) { s.linearization = parseLinearization(v); },
     [](const FilterSpec& s) { return std::string(linearizationName(s.linearization)); }},
    {"iterations", kAll, kInteger, "", 1, 20,
     "Gauss-Newton iterations of each measurement update (1: the EKF's single linearisation)",
     [](FilterSpec& s, std::string_view v) { s.iterations = static_cast<int>(parseIntegerOf(kOptions, "iterations", v)); },
     [](const FilterSpec& s) { return std::to_string(s.iterations); }},
    {"sparsify", kSeif, kChoice, "seif|eseif|conservative", 0, 0,
     "how the robot's links are kept at `active`: the paper's conditioning (seif), the ESEIF's "
     "relocalisation from `beta` observations (eseif: nothing conditioned away), or the paper's "
     "conditioning with H scaled down until it claims no more than before (conservative)",
     [](FilterSpec& s, std::string_view v) { s.seif.sparsify = SeifOptions::parseSparsify(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.sparsify)); }},
    {"active", kSeif, kInteger, "", 1, kMaxLocalLandmarks - 1,
     "theta_x: landmarks kept linked to the robot (the paper: 6)",
     [](FilterSpec& s, std::string_view v) {
       s.seif.active = static_cast<int>(parseIntegerOf(kOptions, "active", v));
     },
     [](const FilterSpec& s) { return std::to_string(s.seif.active); }},
    {"beta", kSeif, kInteger, "", 2, kMaxLocalLandmarks - 1,
     "ESEIF: landmarks whose observations relocalise the robot",
     [](FilterSpec& s, std::string_view v) {
       s.seif.beta = static_cast<int>(parseIntegerOf(kOptions, "beta", v));
     },
     [](const FilterSpec& s) { return std::to_string(s.seif.beta); }},
    {"relax", kSeif, kInteger, "", 0, kIntMax,
     "K: landmarks relaxed per step besides the robot and the active ones (capped at the map size)",
     [](FilterSpec& s, std::string_view v) { s.seif.relax = static_cast<int>(parseIntegerOf(kOptions, "relax", v)); },
     [](const FilterSpec& s) { return std::to_string(s.seif.relax); }},
    {"omega", kSeif, Opt::Kind::Real, "", 0, 2,
     "over-relaxation of the K relaxed landmarks, in (0, 2): each moves omega times its Gauss-Seidel "
     "step (1: eq. 42; near 2 the mean follows a loop closure many times faster)",
     [](FilterSpec& s, std::string_view v) { s.seif.omega = parseBetweenOf(kOptions, "omega", v); },
     [](const FilterSpec& s) { return formatReal(s.seif.omega); }},
    {"mean", kSeif, kChoice, "amortized|exact", 0, 0,
     "mean recovery: amortized (constant time) or exact (a sparse Cholesky solve each step)",
     [](FilterSpec& s, std::string_view v) { s.seif.mean = SeifOptions::parseMean(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.mean)); }},
    {"deactivate", kSeif, kChoice, "weakest|oldest", 0, 0,
     "which landmarks the sparsification deactivates: the weakest-linked or the oldest-seen",
     [](FilterSpec& s, std::string_view v) { s.seif.deactivate = SeifOptions::parseDeactivate(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.deactivate)); }},
    {"stale", kSeif, kInteger, "", 0, kIntMax,
     "deactivate first the active landmarks not observed in the last N steps, the longest unobserved "
     "first (0: off)",
     [](FilterSpec& s, std::string_view v) { s.seif.stale = parseIntegerOf(kOptions, "stale", v); },
     [](const FilterSpec& s) { return std::to_string(s.seif.stale); }},
    {"recovery", kSeif, kChoice, "after-update|before-update", 0, 0,
     "relax the amortized mean before the measurement update (the book's order) or after it",
     [](FilterSpec& s, std::string_view v) { s.seif.recovery = SeifOptions::parseRecovery(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.recovery)); }},
    {"relax-order", kSeif, kChoice, "random|cyclic|wildfire", 0, 0,
     "which K landmarks each step relaxes: the next in map order (cyclic), drawn at random (the "
     "paper), or first the neighbours of landmarks whose mean moved (wildfire), then cyclic",
     [](FilterSpec& s, std::string_view v) { s.seif.relax_order = SeifOptions::parseRelaxOrder(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.relax_order)); }},
    {"wildfire", kSeif, Opt::Kind::Real, "", 0, 100,
     "relax-order=wildfire: the move of a landmark's mean, in its conditional standard deviations, "
     "that queues its neighbours for relaxation",
     [](FilterSpec& s, std::string_view v) { s.seif.wildfire = parseBetweenOf(kOptions, "wildfire", v); },
     [](const FilterSpec& s) { return formatReal(s.seif.wildfire); }},
    {"covariance", kSeif, kChoice, "exact|local|conservative", 0, 0,
     "how poseCovariance() and landmarkCovariance() are recovered: exact (one sparse factorisation "
     "per changed H), local (a bounded blanket's, constant time, never larger than exact) or "
     "conservative (an upper bound kept in constant time, never smaller than exact)",
     [](FilterSpec& s, std::string_view v) { s.seif.covariance = SeifOptions::parseCovariance(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.covariance)); }},
    {"bounds", kSeif, kChoice, "false|true", 0, 0,
     "keep an upper bound on every landmark's covariance, for conservative marginals and gates "
     "(constant time; about 2.4x the cost of a step)",
     [](FilterSpec& s, std::string_view v) { s.seif.bounds = parseBool("bounds", v); },
     [](const FilterSpec& s) { return std::string(s.seif.bounds ? "true" : "false"); }},
    {"blanket", kSeif, kInteger, "", 0, kIntMax,
     "local marginals (gates, covariance=local): at most this many variables besides the queried "
     "ones, the strongest-linked first (0: the whole Markov blanket, unbounded)",
     [](FilterSpec& s, std::string_view v) { s.seif.blanket = static_cast<int>(parseIntegerOf(kOptions, "blanket", v)); },
     [](const FilterSpec& s) { return std::to_string(s.seif.blanket); }},
    {"reanchor", kSeif, Opt::Kind::Length, "", 0, 0,
     "linearization=invariant: re-anchor an observed landmark whose mean moved more than this [m]",
     [](FilterSpec& s, std::string_view v) { s.seif.reanchor = parseLength("reanchor", v); },
     [](const FilterSpec& s) { return formatReal(s.seif.reanchor); }},
    {"rho", kSeif, Opt::Kind::Fraction, "", 0, 0,
     "the journal paper's knob: H and b scaled by 1 - rho at each sparsification (the mean kept, "
     "the covariance inflated; 0: off)",
     [](FilterSpec& s, std::string_view v) { s.seif.rho = parseFraction("rho", v); },
     [](const FilterSpec& s) { return formatReal(s.seif.rho); }},
    {"gauge", kSeif, kChoice, "paper|kept", 0, 0,
     "sparsification on the directions the posterior leaves free (the map moved or turned with "
     "the robot): the paper's rule claims information on them (paper), or none (kept)",
     [](FilterSpec& s, std::string_view v) { s.seif.gauge = SeifOptions::parseGauge(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.gauge)); }},
    {"coarse", kSeif, kChoice, "off|rigid", 0, 0,
     "the amortized mean's coarse level: off (Gauss-Seidel alone; the map lags its posterior "
     "as a whole) or rigid (each step also corrects the map's rigid motion, O(1))",
     [](FilterSpec& s, std::string_view v) { s.seif.coarse = SeifOptions::parseCoarse(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.coarse)); }},
    {"motion", kSeif, kChoice, "immediate|deferred", 0, 0,
     "when motion enters H: at every control (immediate, the paper) or composed into one "
     "increment at the next observation (deferred: one motion update per scan)",
     [](FilterSpec& s, std::string_view v) { s.seif.motion = SeifOptions::parseMotion(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.seif.motion)); }},
    {"seed", kSeif, Opt::Kind::Seed, "", 0, 0, "seed of the random choice of relaxed landmarks",
     [](FilterSpec& s, std::string_view v) { s.seif.seed = parseSeed(v); },
     [](const FilterSpec& s) { return std::to_string(s.seif.seed); }},
    {"init", Opt::Scope::Batch, kChoice, "ekf|seif|odometry", 0, 0,
     "where the batch starts: a filter's estimate (the EKF's or the SEIF's, run alongside) or "
     "odometry alone",
     [](FilterSpec& s, std::string_view v) { s.batch.init = BatchOptions::parseInit(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.batch.init)); }},
    {"solver", Opt::Scope::Batch, kChoice, "cholesky|kkt", 0, 0,
     "the batch's linear solver: sparse Cholesky of the normal equations, or SparseLU of the KKT "
     "system (the cross-check)",
     [](FilterSpec& s, std::string_view v) { s.batch.solver = BatchOptions::parseSolver(v); },
     [](const FilterSpec& s) { return std::string(optionName(s.batch.solver)); }},
}};

void applyProfile(FilterSpec& s, std::string_view v) {
  if (v != "consistent") throw InvalidArgument("unknown profile '" + std::string(v) + "' (expected consistent)");
  for (std::string_view rest = kConsistentProfile; !rest.empty();) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    const std::size_t eq = item.find('=');
    const std::string_view key = item.substr(0, eq);
    for (const FilterOption& o : kOptions) {
      if (o.key == key) o.set(s, item.substr(eq + 1));
    }
  }
}

bool knownFilter(std::string_view name) {
  return name == "ekf" || name == "eif" || name == "seif" || name == "batch";
}

}  // namespace

std::span<const FilterOption> filterOptions() { return kOptions; }

void checkFilterOptions(std::string_view name, const FilterConfig& config, const SeifOptions* seif) {
  FilterSpec spec;
  spec.name = std::string(name);
  spec.linearization = config.linearization;
  spec.iterations = config.iterations;
  if (seif != nullptr) spec.seif = *seif;
  options::checkValues(name, kOptions, spec, [&spec](const FilterOption& o) {
    return takesOption(spec.name, o) && o.kind != FilterOption::Kind::Profile;
  });
}

bool takesOption(std::string_view name, const FilterOption& option) {
  switch (option.scope) {
    case FilterOption::Scope::AllButBatch: return knownFilter(name) && name != "batch";
    case FilterOption::Scope::Seif: return name == "seif";
    case FilterOption::Scope::Batch: return name == "batch";
  }
  return false;
}

std::string canonicalFilterSpec(const FilterSpec& spec) {
  std::string out = spec.name;
  char sep = ':';
  for (const FilterOption& o : kOptions) {
    if (!takesOption(spec.name, o) || o.kind == FilterOption::Kind::Profile) continue;
    out.append(1, sep).append(o.key).append("=").append(o.get(spec));
    sep = ',';
  }
  return out;
}

FilterSpec parseFilterSpec(std::string_view text, Linearization linearization, const SeifOptions& seif) {
  FilterSpec defaults;
  defaults.linearization = linearization;
  defaults.seif = seif;
  return parseFilterSpec(text, defaults);
}

FilterSpec parseFilterSpec(std::string_view text, const FilterSpec& defaults) {
  FilterSpec spec = defaults;
  spec.text = std::string(text);
  const std::size_t colon = text.find(':');
  spec.name = std::string(text.substr(0, colon));
  if (!knownFilter(spec.name)) {
    if (spec.name.find(',') != std::string::npos) badSpec(text, "a list where one filter spec is expected");
    badSpec(text, "unknown filter '" + spec.name + "' (expected ekf, eif, seif or batch)");
  }
  if (colon == std::string_view::npos) return spec;
  std::string_view rest = text.substr(colon + 1);
  if (rest.empty()) badSpec(text, "nothing after ':' (expected key=value,...)");
  std::vector<std::string_view> given;
  for (bool more = true; more;) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    more = comma != std::string_view::npos;
    rest = more ? rest.substr(comma + 1) : std::string_view();
    if (item.empty()) badSpec(text, "an empty option (a ',' too many)");
    const std::size_t eq = item.find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == item.size()) {
      std::string what = "'";  // built by appends: GCC 12's -Wrestrict misfires on "lit" + string&&
      badSpec(text, what.append(item).append("' is not key=value"));
    }
    const std::string_view key = item.substr(0, eq);
    const std::string_view value = item.substr(eq + 1);
    if (std::find(given.begin(), given.end(), key) != given.end()) {
      badSpec(text, "option '" + std::string(key) + "' given twice");
    }
    given.push_back(key);
    const auto option = std::find_if(kOptions.begin(), kOptions.end(), [&](const FilterOption& o) { return o.key == key; });
    if (option == kOptions.end() || !takesOption(spec.name, *option)) {
      if (spec.name == "batch" && key == "linearization") {
        badSpec(text, "the batch MAP relinearises at every iteration; it takes no linearization");
      }
      std::string takes;
      for (const FilterOption& o : kOptions) {
        if (takesOption(spec.name, o)) takes.append(takes.empty() ? "" : ", ").append(o.key);
      }
      badSpec(text, "unknown option '" + std::string(key) + "' for " + spec.name +
                        (takes.empty() ? " (it takes none)" : " (it takes " + takes + ")"));
    }
    try {
      option->set(spec, value);
    } catch (const InvalidArgument& e) {
      badSpec(text, e.what());
    }
  }
  return spec;
}

std::vector<std::string> splitFilterList(std::string_view list) {
  std::vector<std::string> specs;
  const std::string whole(list);
  while (true) {
    const std::size_t comma = list.find(',');
    const std::string_view item = list.substr(0, comma);
    if (item.empty()) {
      throw InvalidArgument(whole.empty() ? std::string("filter list: empty (expected SPEC[,SPEC...])")
                                          : "filter list '" + whole + "': an empty item (a ',' too many)");
    }
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
  for (std::size_t i = 0; i < specs.size(); ++i) {  // two rows of one filter could not be told apart
    if (std::find(specs.begin(), specs.begin() + static_cast<std::ptrdiff_t>(i), specs[i]) != specs.begin() + static_cast<std::ptrdiff_t>(i)) {
      throw InvalidArgument("filter list '" + whole + "': " + specs[i] + " listed twice");
    }
  }
  return specs;
}

std::unique_ptr<SlamFilter> makeFilter(const FilterSpec& spec, const Pose2& start, const FilterConfig& config) {
  if (!start.allFinite()) throw InvalidArgument("the start pose is not finite");
  FilterConfig c = config;
  c.linearization = spec.linearization;
  c.iterations = spec.iterations;
  if (spec.name == "ekf") return std::make_unique<EkfSlam>(start, c);
  if (spec.name == "eif") return std::make_unique<EifSlam>(start, c);
  if (spec.name == "seif") return std::make_unique<SeifSlam>(start, c, spec.seif);
  if (spec.name == "batch") return std::make_unique<BatchMap>(start, c, spec.batch);
  throw InvalidArgument("unknown filter '" + spec.name + "' (expected ekf, eif, seif or batch)");
}

std::unique_ptr<SlamFilter> makeSmoother(const FilterSpec& filter, const Pose2& start, const FilterConfig& config,
                                         const BatchOptions& options) {
  if (filter.name == "batch") throw InvalidArgument("smooth (--smooth): the batch is a smoother already; smooth after ekf, eif or seif");
  FilterConfig inner = config;
  inner.outlier_gate = std::numeric_limits<double>::infinity();  // the smoother gates at its estimate
  return std::make_unique<BatchMap>(start, config, makeFilter(filter, start, inner), options);
}

const SlamFilter* smoothedFilter(const SlamFilter& smoother) {
  const auto* batch = dynamic_cast<const BatchMap*>(&smoother);
  return batch ? batch->filtered() : nullptr;
}

std::unique_ptr<SlamFilter> makeFilter(std::string_view spec, const Pose2& start,
                                       const FilterConfig& config, const SeifOptions& seif_options) {
  FilterSpec defaults;
  defaults.linearization = config.linearization;
  defaults.iterations = config.iterations;
  defaults.seif = seif_options;
  return makeFilter(parseFilterSpec(spec, defaults), start, config);
}

}  // namespace seif
