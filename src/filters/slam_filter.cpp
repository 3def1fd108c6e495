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
  if (it == ids.end()) throw std::out_of_range(name() + ": landmark " + std::to_string(id) + " is not in the map");
  return covariance().middleCols<2>(3 + 2 * (it - ids.begin()));
}

PredictedMeasurement SlamFilter::innovation(const MeasurementModel& sensor, const Pose2& x, const Vec2& y,
                                            const Mat3& Sxx, const Mat32& Sxy, const Mat2& Syy,
                                            const Mat2& R) {
  Mat23 Jx;
  Mat2 Jy;
  PredictedMeasurement p;
  p.z = sensor.predict(x, y, &Jx, &Jy);
  const Mat2 cross = Jx * Sxy * Jy.transpose();
  p.S = Jx * Sxx * Jx.transpose() + cross + cross.transpose() + Jy * Syy * Jy.transpose() + R;
  p.S = (0.5 * (p.S + p.S.transpose())).eval();
  return p;
}

void SlamFilter::requireAssociated(const Observation& z, const char* filter) {
  if (z.landmark < 0) {
    throw ModelError(std::string(filter) + ": an observation has no landmark id (landmark " +
                     std::to_string(z.landmark) + "); this filter needs known data association");
  }
}

}  // namespace seif
