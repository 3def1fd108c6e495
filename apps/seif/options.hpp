#pragma once
// Option groups shared by the commands that run filters.
#include <seif/filters/factory.hpp>
#include <seif/io/dataset.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace seif::cli {

/// Noise of the MRCLAM robots when a dataset has no meta.json (iRobot Create velocity
/// commands, camera range and bearing): tuned once on dataset 6 and documented in README.
NoiseModel mrclamDefaultNoise();

/// --sigma-v/--sigma-w/--sigma-range/--sigma-bearing; unset flags fall back to the
/// dataset's meta.json noise, then to mrclamDefaultNoise().
struct NoiseFlags {
  std::optional<double> sigma_v, sigma_w, sigma_range, sigma_bearing;
  void add(CLI::App& cmd);
  NoiseModel resolve(const std::optional<NoiseModel>& dataset_noise) const;
};

/// --active/--relax/--mean/--deactivate/--seed of the SEIF.
struct SeifFlags {
  int active = 6;
  int relax = 10;
  std::string mean = "amortized";
  std::string deactivate = "weakest";
  std::string recovery = "before-update";
  std::string relax_order = "cyclic";
  std::uint64_t seed = 1;
  void add(CLI::App& cmd);
  SeifOptions resolve() const;
};

nlohmann::json toJson(const NoiseModel& noise);
nlohmann::json toJson(const SeifOptions& options);
nlohmann::json toJson(const FilterStats& stats);

/// A progress bar on stderr when it is a terminal; silent otherwise.
class Progress {
 public:
  explicit Progress(std::string label);
  void operator()(std::size_t done, std::size_t total);
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

/// Writes `j` (pretty-printed) to `file`, creating its folder.
void writeJson(const std::string& file, const nlohmann::json& j);

}  // namespace seif::cli
