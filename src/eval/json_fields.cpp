// JSON spellings shared by the experiments' outputs (src/eval/json_fields.hpp).
#include "json_fields.hpp"

namespace seif {

nlohmann::json toJson(const NoiseModel& n) {
  return {{"sigma_v", n.sigma_v},
          {"sigma_w", n.sigma_w},
          {"sigma_range", n.sigma_range},
          {"sigma_bearing", n.sigma_bearing}};
}

nlohmann::json toJson(const SeifOptions& o) {
  return {{"active", o.max_active},
          {"relax", o.relax},
          {"mean", o.mean == SeifOptions::Mean::Exact ? "exact" : "amortized"},
          {"deactivate", o.deactivate == SeifOptions::Deactivate::Oldest ? "oldest" : "weakest"},
          {"recovery", o.recovery == SeifOptions::Recovery::BeforeMeasurement ? "before-update" : "after-update"},
          {"relax_order", o.relax_order == SeifOptions::RelaxOrder::Cyclic ? "cyclic" : "random"},
          {"sparsify", o.sparsify == SeifOptions::Sparsify::Eseif ? "eseif" : "seif"},
          {"beta", o.eseif_beta},
          {"covariance", o.covariance == SeifOptions::Covariance::Local ? "local" : "exact"},
          {"seed", o.seed}};
}

nlohmann::json toJson(const FilterStats& s) {
  return {{"landmarks", s.landmarks},
          {"links", s.links},
          {"robot_links", s.robot_links},
          {"max_landmark_links", s.max_landmark_links},
          {"blocks_touched", s.blocks_touched}};
}

}  // namespace seif
