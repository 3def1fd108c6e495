#include "options.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run_dataset.hpp>
#include "filters/information_ops.hpp"
#include "core/files.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>

namespace seif::cli {

namespace {

/// `text` without one leading '+' (std::from_chars accepts '-' only).
std::string_view withoutPlus(const std::string& text) {
  std::string_view s(text);
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}

/// The whole of `text` as a T (std::from_chars: decimal, no spaces), or nothing.
template <typename T>
std::optional<T> parseAll(const std::string& text) {
  const std::string_view s = withoutPlus(text);
  T value{};
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

}  // namespace

bool isPositiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

CLI::Validator positiveFinite() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        const auto v = parseAll<double>(input);
        if (v && isPositiveFinite(*v)) return {};
        return "must be finite and > 0, found " + input;
      },
      "FINITE > 0");
}

CLI::Validator nonEmptyPath() {
  return CLI::Validator([](std::string& input) -> std::string { return input.empty() ? "must not be empty" : ""; },
                        "PATH");
}

CLI::Validator integerIn(long long lo, long long hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& input) -> std::string {
        const auto v = parseAll<long long>(input);
        if (!v || *v < lo || *v > hi) return "must be an integer in " + range + ", found " + input;
        input = std::to_string(*v);  // canonical: CLI11 would read 010 as octal
        return {};
      },
      range);
}

CLI::Validator seedValue() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        // from_chars reads no sign into an unsigned type: "-1" is refused, not wrapped.
        const auto v = parseAll<std::uint64_t>(input);
        if (!v) return "must be an integer in [0, " + std::to_string(UINT64_MAX) + "], found " + input;
        input = std::to_string(*v);
        return {};
      },
      "[0, 2^64-1]");
}

void addDetectionFlags(CLI::App& cmd, double& clutter, double& detection_probability) {
  cmd.add_option("--clutter", clutter,
                 "mean number of false detections per scan (Poisson, uniform in the sensor's footprint);\n"
                 "they are observations of no landmark: run them with --association nn|jcbb, or with\n"
                 "known association and --drop-unlabelled (docs/simulator.md)")
      ->check([](const std::string& s) -> std::string {
        const auto v = parseAll<double>(s);
        if (!v || !std::isfinite(*v) || *v < 0.0) return "must be finite and >= 0, found " + s;
        return {};
      })
      ->capture_default_str();
  cmd.add_option("--detection-probability", detection_probability,
                 "probability that a landmark in range is reported (each landmark, each scan)")
      ->check([](const std::string& s) -> std::string {
        const auto v = parseAll<double>(s);
        if (!v || !(*v >= 0.0 && *v <= 1.0)) return "must be in [0, 1], found " + s;
        return {};
      })
      ->capture_default_str();
}

void requireOutputFolder(const std::string& out) {
  if (out.empty()) throw InvalidArgument("--out: must not be empty");
  requireWritableDirectory(out);
}

void NoiseFlags::add(CLI::App& cmd) {
  // A standard deviation whose variance and information are finite and not zero
  // (resolveNoise() holds the same bounds for every source).
  const CLI::Validator positive(
      [](std::string& input) -> std::string {
        const auto v = parseAll<double>(input);
        if (!v || !isPositiveFinite(*v)) return "must be finite and > 0, found " + input;
        if (*v < 1e-100 || *v > 1e100) return "must be in [1e-100, 1e100], found " + input;
        return {};
      },
      "FINITE > 0");
  const struct {
    const char* flag;
    const char* name;
    const char* help;
  } flags[] = {
      {"--sigma-v", "sigma_v", "velocity model: forward-velocity noise [m/s, or m/s*sqrt(s) as a rate]"},
      {"--sigma-w", "sigma_w", "velocity model: rotational-velocity noise [rad/s, or rad/s*sqrt(s) as a rate]"},
      {"--sigma-speed", "sigma_speed", "Ackermann model: encoder speed noise [m/s, or m/s*sqrt(s) as a rate]"},
      {"--sigma-steering", "sigma_steering", "Ackermann model: steering noise [rad, or rad*sqrt(s) as a rate]"},
      {"--sigma-range", "sigma_range", "range-bearing sensor: range noise [m]"},
      {"--sigma-bearing", "sigma_bearing", "range-bearing sensor: bearing noise [rad]"}};
  for (const auto& f : flags) cmd.add_option(f.flag, sigmas[f.name], f.help)->check(positive);
  cmd.add_option("--noise-form", form,
                 "per-step (the paper's: the control noise is the same for every step) or rate "
                 "(a noise density: the injected noise grows with the step's duration); default: "
                 "the format's (simulated folders per-step, recorded logs rate)")
      ->check(CLI::IsMember({"per-step", "rate"}));
  cmd.add_option("--isam-landmarks", isam_landmarks,
                 "how an iSAM LANDMARK record (x, y, covariance) is read: cartesian (the point with its\n"
                 "covariance) or gtsam (as GTSAM's loader: bearing atan2(y, x), range hypot(x, y),\n"
                 "sigma_bearing = sqrt(m11 / 10), sigma_range = sqrt(m11)), so that costs compare with GTSAM's")
      ->check(CLI::IsMember({"cartesian", "gtsam"}))
      ->capture_default_str();
  cmd.add_option("--detections", detections,
                 "Victoria Park: associated (tree_observations_associated_UTS.txt, trees named by the\n"
                 "UTS association) or raw (tree_detections.txt, the tree detector's output with its\n"
                 "spurious detections, no landmark ids: for unknown data association; the UTS ids are\n"
                 "kept only to score an association). Another format with raw is a usage error")
      ->check(CLI::IsMember({"associated", "raw"}))
      ->capture_default_str();
}

DatasetOptions NoiseFlags::resolve() const {
  DatasetOptions o;
  for (const auto& [name, value] : sigmas) {
    if (value) o.noise[name] = *value;
  }
  if (!form.empty()) o.noise_form = parseNoiseForm(form);
  o.isam_landmarks_as_gtsam = isam_landmarks == "gtsam";
  o.detections = parseDetections(detections);
  return o;
}

CLI::Validator filterSpecs() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        try {
          for (const std::string& f : splitFilterList(s)) parseFilterSpec(f);
        } catch (const InvalidArgument& e) {
          return e.what();
        }
        return {};
      },
      "SPEC[,SPEC...]");
}

namespace {

/// "a|b|c" -> {a, b, c}: an option table's choices, for CLI::IsMember.
std::vector<std::string> splitChoices(std::string_view choices) {
  std::vector<std::string> out;
  for (std::string_view rest = choices; !rest.empty();) {
    const std::size_t bar = rest.find('|');
    out.emplace_back(rest.substr(0, bar));
    rest = bar == std::string_view::npos ? std::string_view() : rest.substr(bar + 1);
  }
  return out;
}

}  // namespace

void FilterFlags::add(CLI::App& cmd, bool batch) {
  FilterSpec defaults;
  defaults.name = "seif";
  for (const FilterOption& o : filterOptions()) {
    if (o.kind == FilterOption::Kind::Profile) continue;
    if (o.scope == FilterOption::Scope::Batch && !batch) continue;
    std::string& value = values[std::string(o.key)];
    value = o.get(defaults);
    const std::string scope = o.scope == FilterOption::Scope::Seif    ? "SEIF: "
                              : o.scope == FilterOption::Scope::Batch ? "batch (and --smooth): "
                                                                      : "";
    CLI::Option* flag = cmd.add_option("--" + std::string(o.key), value, scope + std::string(o.help));
    switch (o.kind) {
      case FilterOption::Kind::Choice: flag->check(CLI::IsMember(splitChoices(o.choices))); break;
      case FilterOption::Kind::Integer: flag->transform(integerIn(o.min, o.max)); break;
      case FilterOption::Kind::Seed: flag->transform(seedValue()); break;
      case FilterOption::Kind::Profile: break;
      case FilterOption::Kind::Length:
      case FilterOption::Kind::Fraction:
      case FilterOption::Kind::Real:  // the table's own parser checks the range and words the error
        flag->check([set = o.set](const std::string& v) -> std::string {
          FilterSpec scratch;
          try {
            set(scratch, v);
          } catch (const InvalidArgument& e) {
            return e.what();
          }
          return {};
        });
        break;
    }
    flag->capture_default_str();
    flags_.emplace_back(&o, flag);
  }
}

std::vector<std::string> FilterFlags::ignoredBy(const std::string& filter, bool smooth) const {
  const std::string name = filter.substr(0, filter.find(':'));
  std::vector<std::string> ignored;
  for (const auto& [o, flag] : flags_) {
    if (flag->count() == 0) continue;
    const bool seif_only = o->scope == FilterOption::Scope::Seif && (name == "ekf" || name == "eif");
    const bool batch_only = o->scope == FilterOption::Scope::Batch && name != "batch" && !smooth;
    if (seif_only) ignored.push_back("--" + std::string(o->key) + " is a SEIF option: --filter " + name + " does not take it");
    if (batch_only) {
      ignored.push_back("--" + std::string(o->key) + " sets the batch MAP: --filter " + name + " without --smooth does not run it");
    }
  }
  return ignored;
}

FilterSpec FilterFlags::resolve() const {
  FilterSpec spec;
  spec.name = "seif";
  for (const FilterOption& o : filterOptions()) {
    const auto it = values.find(std::string(o.key));
    if (it != values.end()) o.set(spec, it->second);
  }
  return spec;
}

std::string filterSpecHelp() {
  std::string all, seif, batch;
  for (const FilterOption& o : filterOptions()) {
    std::string& list = o.scope == FilterOption::Scope::Seif ? seif : o.scope == FilterOption::Scope::Batch ? batch : all;
    list.append(list.empty() ? "" : ", ").append(o.key);
    if (o.kind == FilterOption::Kind::Choice || o.kind == FilterOption::Kind::Profile) list.append("=").append(o.choices);
  }
  return "keys: " + all + " (every filter but the batch); for the seif " + seif + "; for the batch " + batch +
         " (the flags of the same names set the defaults)";
}

Progress::Progress(std::string label) : label_(std::move(label)), tty_(isatty(STDERR_FILENO) != 0) {}

void Progress::operator()(std::size_t done, std::size_t total) {
  if (!tty_ || total == 0) return;
  const int width = 30;
  const int filled = static_cast<int>(width * done / total);
  std::fprintf(stderr, "\r%s [%.*s%*s] %3zu%%", label_.c_str(), filled,
               "##############################", width - filled, "", 100 * done / total);
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::operator()(double fraction) {
  constexpr std::size_t kSteps = 1000;
  (*this)(static_cast<std::size_t>(std::clamp(fraction, 0.0, 1.0) * kSteps), kSteps);
}

Progress::~Progress() {
  if (drawn_) std::fprintf(stderr, "\n");
}

namespace {

/// Runs `argv` (argv[0] an absolute path) without a shell; its exit status, or -1.
int runProgram(std::vector<std::string> argv, bool quiet) {
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (quiet) {
      std::freopen("/dev/null", "w", stdout);
      std::freopen("/dev/null", "w", stderr);
    }
    std::vector<char*> cargs;
    for (std::string& a : argv) cargs.push_back(a.data());
    cargs.push_back(nullptr);
    execv(cargs[0], cargs.data());
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

bool renderFigure(const std::string& script, const std::vector<std::string>& args) {
  const std::string python = "/usr/bin/python3";
  const std::string path = std::string(SEIF_FIGURE_SCRIPT_DIR) + "/figures/" + script;
  std::vector<std::string> argv = {python, path};
  argv.insert(argv.end(), args.begin(), args.end());
  std::string later;
  for (const std::string& a : argv) later += (later.empty() ? "" : " ") + a;
  if (access(python.c_str(), X_OK) != 0 || access(path.c_str(), R_OK) != 0 ||
      runProgram({python, "-c", "import matplotlib"}, true) != 0) {
    std::printf("figures: not rendered (needs %s with matplotlib: apt-get install "
                "python3-matplotlib); render later with: %s\n",
                python.c_str(), later.c_str());
    return false;
  }
  const int code = runProgram(argv, false);
  if (code != 0) {
    std::printf("figures: `%s` failed (exit %d)\n", later.c_str(), code);
    return false;
  }
  return true;
}


void AssociationFlags::add(CLI::App& cmd, bool tuning) {
  const AssociationOptions defaults;
  for (const AssociationOption& o : associationOptions()) {
    if (o.tuning && !tuning) continue;
    const std::string key(o.key);
    std::string& value = values[key];
    value = o.get(defaults);
    if (o.kind == AssociationOption::Kind::Flag) {
      flags_.emplace_back(key, cmd.add_flag_callback("--" + key, [&value] { value = "true"; }, std::string(o.help)));
      continue;
    }
    CLI::Option* flag = cmd.add_option("--" + key, value, std::string(o.help));
    flags_.emplace_back(key, flag);
    if (o.kind == AssociationOption::Kind::Choice) {
      flag->check(CLI::IsMember(splitChoices(o.choices)));
    } else {
      flag->check([&o](const std::string& v) -> std::string {  // the table's own parser
        AssociationOptions scratch;
        try {
          o.set(scratch, v);
        } catch (const InvalidArgument& e) {
          return e.what();
        }
        return {};
      });
    }
    flag->capture_default_str();
  }
}

std::vector<std::string> AssociationFlags::ignoredByKnown() const {
  std::vector<std::string> ignored;
  for (const auto& [key, flag] : flags_) {
    // --association itself, and --drop-unlabelled, which known association reads.
    if (flag->count() == 0 || key == "association" || key == "drop-unlabelled") continue;
    ignored.push_back("--" + key + " tunes nn and jcbb: --association known does not read it");
  }
  return ignored;
}

AssociationOptions AssociationFlags::resolve() const {
  AssociationOptions o;
  for (const AssociationOption& option : associationOptions()) {
    const auto it = values.find(std::string(option.key));
    if (it != values.end()) option.set(o, it->second);
  }
  return o;
}

}  // namespace seif::cli
