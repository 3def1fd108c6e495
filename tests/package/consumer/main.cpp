// A downstream project: builds against the installed seif package with only the public
// umbrella header, drives a SEIF through a few cycles and reads the pose, a marginal and a
// predicted measurement.
#include <seif/seif.hpp>

#include <cmath>
#include <iostream>
#include <memory>

int main() {
  seif::FilterConfig config;
  config.motion = std::make_shared<seif::VelocityModel>(0.05, 0.02, seif::NoiseForm::PerStep);
  config.sensor = std::make_shared<seif::RangeBearingModel>(0.05, 0.02);
  auto filter = seif::makeFilter("seif", seif::Pose2::Zero(), config);
  for (int k = 0; k < 10; ++k) {
    filter->predict(seif::VelocityControl{1.0, 0.1, 0.1});
    const seif::Observation z[] = {{7, seif::Vec2(2.0 - 0.1 * k, 0.2 + 0.01 * k), std::nullopt},
                                   {8, seif::Vec2(3.0 - 0.1 * k, -0.3), std::nullopt}};
    filter->update(z);
  }
  const int ids[] = {7, 8};
  const seif::Marginal m = filter->marginal(ids, true, seif::MarginalMode::Exact);
  const seif::PredictedMeasurement p = filter->predictMeasurement(7, *config.sensor, config.sensor->noise());
  std::cout << "landmarks " << filter->landmarkIds().size() << " pose " << filter->pose().transpose()
            << " joint marginal " << m.covariance.rows() << "x" << m.covariance.cols() << " S(0,0) " << p.S(0, 0) << "\n";
  const bool ok = filter->landmarkIds().size() == 2 && filter->pose().allFinite() && m.covariance.rows() == 7 &&
                  p.S.determinant() > 0.0;
  try {
    filter->landmark(99);
    return 1;
  } catch (const seif::UnknownLandmark& e) {
    std::cout << "unknown landmark: " << e.what() << "\n";
  }
  return ok ? 0 : 1;
}
