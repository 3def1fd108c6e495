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
  throw InvalidArgument("unknown linearization '" + std::string(s) + "' (expected standard or fej)");
}

std::string_view linearizationName(Linearization l) {
  return l == Linearization::FirstEstimates ? "fej" : "standard";
}

SlamFilter::SlamFilter(const FilterConfig& config)
    : motion_(config.motion ? config.motion
                            : std::make_shared<VelocityModel>(config.noise.sigma_v, config.noise.sigma_w,
                                                              NoiseForm::PerStep)),
      sensor_(config.sensor ? config.sensor
                            : std::make_shared<RangeBearingModel>(config.noise.sigma_range,
                                                                  config.noise.sigma_bearing)) {}

Eigen::Matrix<double, Eigen::Dynamic, 2> SlamFilter::landmarkCovarianceColumns(int id) const {
  const std::vector<int>& ids = landmarkIds();
  const auto it = std::find(ids.begin(), ids.end(), id);
  if (it == ids.end()) throw UnknownLandmark(name(), id);
  return covariance().middleCols<2>(3 + 2 * (it - ids.begin()));
}

PredictedMeasurement SlamFilter::predictMeasurement(int id, const MeasurementModel& sensor, const Mat2& R,
                                                   MarginalMode mode) const {
  const int ids[1] = {id};
  const Marginal m = marginal(ids, true, mode);
  // S = J P J^T + R with J = [J_x J_y] over the joint marginal P of pose and landmark.
  Eigen::Matrix<double, 2, 5> J;
  Mat23 J_x;
  Mat2 J_y;
  PredictedMeasurement p;
  p.z = sensor.predict(m.mean.head<3>(), m.mean.tail<2>(), &J_x, &J_y);
  J << J_x, J_y;
  p.S = J * m.covariance * J.transpose() + R;
  p.S = (0.5 * (p.S + p.S.transpose())).eval();
  return p;
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
  throw InvalidArgument("unknown marginal mode '" + std::string(s) + "' (expected exact or local)");
}

std::string_view marginalModeName(MarginalMode m) { return m == MarginalMode::Local ? "local" : "exact"; }

}  // namespace seif
