// A downstream project: builds against the installed seif package and runs one step.
#include <seif/filters/ekf_slam.hpp>

#include <cmath>
#include <iostream>

int main() {
  seif::FilterConfig config;
  seif::EkfSlam ekf(Eigen::Vector3d::Zero(), config);
  ekf.predict(seif::VelocityControl{1.0, 0.1, 0.1});
  const seif::Observation z[] = {{7, seif::Vec2(1.0, 0.2), std::nullopt}};
  ekf.update(z);
  std::cout << "landmarks " << ekf.landmarkIds().size() << " pose " << ekf.pose().transpose() << "\n";
  return (ekf.landmarkIds().size() == 1 && std::isfinite(ekf.pose().x())) ? 0 : 1;
}
