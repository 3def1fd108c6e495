// The right-invariant EKF in standard coordinates (src/filters/invariant.hpp).
#include "filters/invariant.hpp"

#include <cmath>

namespace seif::invariant {

namespace {

/// J v, J = [[0, -1], [1, 0]] (a quarter turn).
Vec2 quarterTurn(const Vec2& v) { return Vec2(-v.y(), v.x()); }

Mat2 rotation(double t) {
  const double c = std::cos(t), s = std::sin(t);
  Mat2 R;
  R << c, -s, s, c;
  return R;
}

}  // namespace

Eigen::VectorXd leverArms(const Eigen::VectorXd& s) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(s.size());
  c.head<2>() = quarterTurn(s.head<2>());
  for (Eigen::Index i = 3; i + 1 < s.size(); i += 2) c.segment<2>(i) = quarterTurn(s.segment<2>(i));
  return c;
}

Mat2 leftJacobian(double t) {
  double a = 0.0, b = 0.0;  // sin t / t and (1 - cos t) / t
  if (std::abs(t) < 1e-4) {  // series: the closed forms lose digits near 0
    const double t2 = t * t;
    a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
    b = t / 2.0 - t * t2 / 24.0;
  } else {
    a = std::sin(t) / t;
    b = (1.0 - std::cos(t)) / t;
  }
  Mat2 B;
  B << a, -b, b, a;
  return B;
}

Eigen::VectorXd retract(const Eigen::VectorXd& s, const Eigen::VectorXd& delta) {
  const double dt = delta(2);
  const Mat2 R = rotation(dt), B = leftJacobian(dt);
  Eigen::VectorXd out(s.size());
  const auto point = [&](Eigen::Index i) {
    const Vec2 p = s.segment<2>(i);
    const Vec2 xi = delta.segment<2>(i) - dt * quarterTurn(p);
    out.segment<2>(i) = R * p + B * xi;
  };
  point(0);
  out(2) = s(2) + dt;
  for (Eigen::Index i = 3; i + 1 < s.size(); i += 2) point(i);
  return out;
}

void reanchorCovariance(Eigen::MatrixXd& P, const Eigen::VectorXd& dc) {
  const Eigen::VectorXd col = P.col(2);
  const double ptt = P(2, 2);
  P.noalias() += dc * col.transpose();
  P.noalias() += col * dc.transpose();
  P.noalias() += ptt * dc * dc.transpose();
}

void reanchorInformation(Eigen::MatrixXd& H, const Eigen::VectorXd& dc) {
  const Eigen::VectorXd q = H * dc;
  const double a = dc.dot(q);
  H.col(2) -= q;
  H.row(2) -= q.transpose();
  H(2, 2) += a;
}

Vec2 anchoredHeadingColumn(const Mat2& J_y, const Vec2& a_p, const Vec2& a_l) {
  return -J_y * quarterTurn(a_l - a_p);
}

}  // namespace seif::invariant
