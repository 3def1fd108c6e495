#include <seif/filters/eif_slam.hpp>
#include <seif/filters/ekf_slam.hpp>
#include <seif/filters/factory.hpp>

#include <stdexcept>
#include <string>

namespace seif {

std::unique_ptr<SlamFilter> makeFilter(std::string_view name, const Pose2& start,
                                       const FilterConfig& config,
                                       const SeifOptions& seif_options) {
  if (name == "ekf") return std::make_unique<EkfSlam>(start, config);
  if (name == "eif") return std::make_unique<EifSlam>(start, config);
  if (name == "seif") return std::make_unique<SeifSlam>(start, config, seif_options);
  throw std::invalid_argument("unknown filter '" + std::string(name) +
                              "' (expected ekf, eif or seif)");
}

}  // namespace seif
