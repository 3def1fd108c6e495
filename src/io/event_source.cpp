// Format names and the noise rule shared by the readers (include/seif/io/event_source.hpp).
#include <seif/core/errors.hpp>
#include <seif/io/event_source.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace seif {
namespace {
constexpr std::pair<DatasetFormat, std::string_view> kFormats[] = {
    {DatasetFormat::Auto, "auto"},
    {DatasetFormat::Mrclam, "mrclam"},
    {DatasetFormat::VictoriaPark, "victoria-park"},
    {DatasetFormat::Isam, "isam"},
    {DatasetFormat::G2o, "g2o"}};
}  // namespace

DatasetFormat parseDatasetFormat(std::string_view name) {
  for (const auto& [format, n] : kFormats) {
    if (n == name) return format;
  }
  throw InvalidArgument("unknown dataset format '" + std::string(name) +
                              "' (expected auto, mrclam, victoria-park, isam or g2o)");
}

std::string_view datasetFormatName(DatasetFormat format) {
  for (const auto& [f, n] : kFormats) {
    if (f == format) return n;
  }
  return "?";
}

Detections parseDetections(std::string_view name) {
  if (name == "associated") return Detections::Associated;
  if (name == "raw") return Detections::Raw;
  throw InvalidArgument("unknown detections '" + std::string(name) + "' (expected associated or raw)");
}

std::string_view detectionsName(Detections detections) {
  return detections == Detections::Raw ? "raw" : "associated";
}

void checkNoiseNames(const DatasetOptions& options, const std::vector<std::string>& known, std::string_view format) {
  for (const auto& [name, value] : options.noise) {
    bool found = false;
    for (const std::string& k : known) found = found || k == name;
    if (found) continue;
    std::string list;
    for (const std::string& k : known) list.append(list.empty() ? "" : ", ").append(k);
    throw InvalidArgument("the " + std::string(format) + " format has no noise value '" + name + "'" +
                                (known.empty() ? std::string(" (its noise comes from the file)")
                                               : " (it takes " + list + ")"));
  }
}

double resolveNoise(DatasetInfo& info, const DatasetOptions& options, const std::string& name,
                    const std::string& unit, std::optional<double> from_file, const std::string& file_source,
                    double default_value) {
  double value = default_value;
  std::string source = "default for " + info.format;
  if (const auto it = options.noise.find(name); it != options.noise.end()) {
    value = it->second;
    source = "command line";
  } else if (from_file) {
    value = *from_file;
    source = file_source;
  }
  // Bounded so that the variance and the information it gives are finite and not zero.
  if (!std::isfinite(value) || !(value > 0.0) || value < 1e-100 || value > 1e100) {
    std::ostringstream msg;
    msg << name << (std::isfinite(value) && value > 0.0 ? " must be in [1e-100, 1e100]" : " must be finite and > 0")
        << ", found " << value << " (" << source << ")";
    throw InvalidArgument(msg.str());
  }
  info.noise.push_back({name, value, unit, source});
  return value;
}

}  // namespace seif
