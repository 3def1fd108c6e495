#include <seif/core/errors.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/models/velocity_model.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace seif {

Linearization parseLinearization(std::string_view s) {
  if (s == "standard") return Linearization::Standard;
  if (s == "fej") return Linearization::FirstEstimates;
  if (s == "invariant") return Linearization::Invariant;
  if (s == "oc") return Linearization::ObservabilityConstrained;
  throw InvalidArgument("unknown linearization '" + std::string(s) + "' (expected standard, fej, invariant or oc)");
}

std::string_view linearizationName(Linearization l) {
  switch (l) {
    case Linearization::Standard: return "standard";
    case Linearization::FirstEstimates: return "fej";
    case Linearization::Invariant: return "invariant";
    case Linearization::ObservabilityConstrained: return "oc";
  }
  return "standard";
}

FilterConfig paperFilterConfig(const NoiseModel& noise) {
  FilterConfig c;
  c.motion = std::make_shared<VelocityModel>(noise.sigma_v, noise.sigma_w, NoiseForm::PerStep);
  c.sensor = std::make_shared<RangeBearingModel>(noise.sigma_range, noise.sigma_bearing);
  return c;
}

namespace {

template <typename Model>
std::shared_ptr<const Model> required(const std::shared_ptr<const Model>& model, const char* what) {
  if (!model) {
    throw InvalidArgument(std::string("FilterConfig: no ") + what +
                          " model (set config.motion and config.sensor, e.g. with paperFilterConfig(noise) "
                          "or a dataset's DatasetInfo)");
  }
  return model;
}

}  // namespace

SlamFilter::SlamFilter(const FilterConfig& config)
    : motion_(required(config.motion, "motion")), sensor_(required(config.sensor, "sensor")) {
  // Each filter starts from the variance these give (0: a known start; the information
  // filters need > 0, startInformation()).
  for (Eigen::Index i = 0; i < 3; ++i) {
    const double s = config.initial_pose_sigma(i);
    if (!(s >= 0.0 && s <= 1e100)) {
      throw InvalidArgument("FilterConfig: initial_pose_sigma must be in [0, 1e100], found " + std::to_string(s) +
                            " in component " + std::to_string(i));
    }
  }
}

Eigen::Matrix<double, Eigen::Dynamic, 2> SlamFilter::landmarkCovarianceColumns(int id) const {
  const std::vector<int>& ids = landmarkIds();
  const auto it = std::find(ids.begin(), ids.end(), id);
  if (it == ids.end()) throw UnknownLandmark(name(), id);
  return covariance().middleCols<2>(3 + 2 * (it - ids.begin()));
}

PredictedMeasurement predictFromMarginal(const MeasurementModel& sensor, const Marginal& joint,
                                         Eigen::Index landmark_row, const Mat2& R, Mat23* J_x_out, Mat2* J_y_out) {
  const Eigen::Index c = landmark_row;
  Mat23 J_x;
  Mat2 J_y;
  PredictedMeasurement p;
  p.z = sensor.predict(joint.mean.head<3>(), joint.mean.segment<2>(c), &J_x, &J_y);
  // S = J P J^T + R with J = [J_x J_y] over the pose's and the landmark's blocks of P
  const Eigen::MatrixXd& P = joint.covariance;
  const Mat23 JP_x = J_x * P.topLeftCorner<3, 3>() + J_y * P.block<2, 3>(c, 0);
  const Mat2 JP_y = J_x * P.block<3, 2>(0, c) + J_y * P.block<2, 2>(c, c);
  const Mat2 S = JP_x * J_x.transpose() + JP_y * J_y.transpose() + R;
  p.S = 0.5 * (S + S.transpose());
  if (J_x_out) *J_x_out = J_x;
  if (J_y_out) *J_y_out = J_y;
  return p;
}

PredictedMeasurement SlamFilter::predictMeasurement(int id, const MeasurementModel& sensor, const Mat2& R,
                                                   MarginalMode mode) const {
  const int ids[1] = {id};
  return predictFromMarginal(sensor, marginal(ids, true, mode), 3, R);
}

std::vector<Eigen::Index> SlamFilter::stateIndices(std::span<const int> slots, bool pose) {
  std::vector<Eigen::Index> rows;
  rows.reserve(3 + 2 * slots.size());
  if (pose) {
    for (Eigen::Index i = 0; i < 3; ++i) rows.push_back(i);
  }
  for (int s : slots) {
    rows.push_back(3 + 2 * static_cast<Eigen::Index>(s));
    rows.push_back(4 + 2 * static_cast<Eigen::Index>(s));
  }
  return rows;
}

MarginalMode parseMarginalMode(std::string_view s) {
  if (s == "exact") return MarginalMode::Exact;
  if (s == "local") return MarginalMode::Local;
  if (s == "conservative") return MarginalMode::Conservative;
  throw InvalidArgument("unknown marginal mode '" + std::string(s) + "' (expected exact, local or conservative)");
}

std::string_view marginalModeName(MarginalMode m) {
  switch (m) {
    case MarginalMode::Local:
      return "local";
    case MarginalMode::Conservative:
      return "conservative";
    case MarginalMode::Exact:
      break;
  }
  return "exact";
}

}  // namespace seif
