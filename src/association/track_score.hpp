#pragma once
// The track score's terms (ConfirmRule::Score; Blackman & Popoli 1999, §6.2): Wald's
// sequential probability ratio test of "a landmark" against "clutter", one term a scan.
#include <seif/association/association.hpp>

#include <Eigen/Cholesky>

#include <cmath>
#include <numbers>

namespace seif {

/// A sighting with innovation nu and covariance S: log(P_D N(nu; 0, S) / lambda), lambda the
/// clutter density in the measurement's units. 0 when S is not positive definite.
inline double trackSightingScore(const Vec2& nu, const Mat2& S, double detection_probability, double log_clutter) {
  const Eigen::LLT<Mat2> llt(S);
  if (llt.info() != Eigen::Success) return 0.0;
  const Mat2 L = llt.matrixL();
  const double log_det = 2.0 * (std::log(L(0, 0)) + std::log(L(1, 1)));
  const double log_density = -0.5 * nu.dot(llt.solve(nu)) - 0.5 * log_det - std::log(2.0 * std::numbers::pi);
  return std::log(detection_probability) + log_density - log_clutter;
}

/// A scan in which the landmark lay in the sensor's footprint unseen: log(1 - P_D).
inline double trackMissScore(double detection_probability) { return std::log1p(-detection_probability); }

/// Wald's thresholds for error probabilities alpha (confirming clutter) and beta (removing a
/// landmark): confirmed at log((1 - beta) / alpha), removed at log(beta / (1 - alpha)).
inline double trackConfirmScore() { return std::log((1.0 - kTrackFalseDelete) / kTrackFalseConfirm); }
inline double trackDeleteScore() { return std::log(kTrackFalseDelete / (1.0 - kTrackFalseConfirm)); }

}  // namespace seif
