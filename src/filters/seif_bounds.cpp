// Conservative covariances of the SEIF: seif_bounds.hpp has the derivation.
#include "filters/seif_bounds.hpp"

#include <seif/core/errors.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>

namespace seif {

namespace {

[[noreturn]] void notPositive(const SeifStore& store, const char* what) {
  throw NumericError("seif: after " + std::to_string(store.step()) + " motion updates: " + what +
                     " is not positive definite (conservative covariance)");
}

Mat2 symmetric(const Mat2& A) { return 0.5 * (A + A.transpose()); }

}  // namespace

Mat2 tighterBound(const Mat2& A, const Mat2& B) {
  // det(B + t (A - B)) = alpha t^2 + beta t + det B over t in [0, 1].
  const Mat2 D = A - B;
  const double alpha = D(0, 0) * D(1, 1) - D(0, 1) * D(1, 0);
  const double beta = B(0, 0) * D(1, 1) + B(1, 1) * D(0, 0) - B(0, 1) * D(1, 0) - B(1, 0) * D(0, 1);
  double t = A.determinant() < B.determinant() ? 1.0 : 0.0;
  if (alpha > 0.0) {
    const double s = -beta / (2.0 * alpha);
    if (s > 0.0 && s < 1.0) t = s;
  }
  return symmetric(B + t * D);
}

BoundWorkspace::BoundWorkspace() { members.reserve(kMaxLocalLandmarks); }

bool conservativeCovariance(const SeifStore& store, std::span<const int> slots, Eigen::Ref<Eigen::MatrixXd> out,
                            BoundWorkspace& ws) {
  // I: the robot, the active landmarks, the queried passive ones.
  std::vector<int>& I = ws.members;
  I.clear();
  for (const SeifStore::RobotLink& l : store.robotLinks()) I.push_back(l.slot);
  for (int slot : slots) {
    if (store.node(slot).active < 0 && std::find(I.begin(), I.end(), slot) == I.end()) {
      if (I.size() == static_cast<std::size_t>(kMaxLocalLandmarks)) return false;
      I.push_back(slot);
    }
  }
  const auto position = [&](int slot) -> Eigen::Index {  // of a landmark in I, or -1
    const auto it = std::find(I.begin(), I.end(), slot);
    return it == I.end() ? -1 : 3 + 2 * static_cast<Eigen::Index>(it - I.begin());
  };
  const auto n = 3 + 2 * static_cast<Eigen::Index>(I.size());
  const auto q = 3 + 2 * static_cast<Eigen::Index>(slots.size());
  ws.H.setZero(n, n);
  ws.H.topLeftCorner<3, 3>() = store.robotInformation();
  for (std::size_t i = 0; i < I.size(); ++i) {
    const SeifStore::Node& a = store.node(I[i]);
    const Eigen::Index r = 3 + 2 * static_cast<Eigen::Index>(i);
    ws.H.block<2, 2>(r, r) = a.H;
    if (a.active >= 0) {
      const Mat32& H_xa = store.robotLinks()[static_cast<std::size_t>(a.active)].H;
      ws.H.block<3, 2>(0, r) = H_xa;
      ws.H.block<2, 3>(r, 0) = H_xa.transpose();
    }
    for (const SeifStore::Link& l : a.links) {
      const Eigen::Index c = position(l.slot);
      if (c >= 0) ws.H.block<2, 2>(r, c) = l.H;
    }
  }
  ws.E.setZero(n, q);
  ws.E.topLeftCorner<3, 3>().setIdentity();
  for (std::size_t k = 0; k < slots.size(); ++k) {
    ws.E.block<2, 2>(position(slots[k]), 3 + 2 * static_cast<Eigen::Index>(k)).setIdentity();
  }
  const Eigen::LLT<LocalMatrix> llt(ws.H);
  if (llt.info() != Eigen::Success) notPositive(store, "the information of the robot's block");
  ws.Z = llt.solve(ws.E);
  out.noalias() = ws.E.transpose() * ws.Z;
  // The links leaving I, one term each of (1): for member a (rows Z_a of Z) and outside c,
  // M B_c M^T = Z_a^T (H_ac B_c H_ac^T) Z_a, whose trace is tr(B_c H_ac^T (Z_a Z_a^T) H_ac);
  // the terms of one member are summed as 2x2 matrices before they meet Z.
  const auto forEachTerm = [&](const auto& term) {
    for (std::size_t i = 0; i < I.size(); ++i) {
      const Eigen::Index r = 3 + 2 * static_cast<Eigen::Index>(i);
      const Mat2 G = ws.Z.middleRows(r, 2) * ws.Z.middleRows(r, 2).transpose();
      for (const SeifStore::Link& l : store.node(I[i]).links) {
        if (position(l.slot) >= 0) continue;
        const Mat2& B = store.node(l.slot).bound;
        term(i, (B * l.H.transpose() * G * l.H).trace(), l.H, B);
      }
    }
  };
  double total = 0.0;  // sum_k sqrt(a_k): w_k = sqrt(a_k) / total
  forEachTerm([&](std::size_t, double a, const Mat2&, const Mat2&) { total += std::sqrt(a); });
  std::size_t member = I.size();
  Mat2 S = Mat2::Zero();  // sum over the member's terms of H_ac B_c H_ac^T / w_k
  const auto flush = [&] {
    if (member == I.size()) return;
    const Eigen::Index r = 3 + 2 * static_cast<Eigen::Index>(member);
    out.noalias() += ws.Z.middleRows(r, 2).transpose() * S * ws.Z.middleRows(r, 2);
  };
  forEachTerm([&](std::size_t i, double a, const Mat2& H_ac, const Mat2& B) {
    if (i != member) {
      flush();
      member = i;
      S.setZero();
    }
    if (a > 0.0) S.noalias() += (total / std::sqrt(a)) * (H_ac * B * H_ac.transpose());
  });
  flush();
  out = (0.5 * (out + out.transpose())).eval();
  return true;
}

Mat3 conservativePoseCovariance(const SeifStore& store, BoundWorkspace& ws) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 3, 3> C(3, 3);
  conservativeCovariance(store, {}, C, ws);  // the robot and the active landmarks always fit
  return C;
}

void tightenBounds(SeifStore& store, std::span<const int> slots, const LocalMatrix& prior, const LocalMatrix& added) {
  const Eigen::Index n = added.rows(), known = prior.rows();
  // (C^-1 + I)^-1, the fresh landmarks' prior information zero. Tightening is optional (the
  // bounds before it still hold): a bound too ill-conditioned to invert is left as it is.
  LocalMatrix posterior = added;
  {
    const Eigen::LLT<LocalMatrix> llt(prior);
    if (llt.info() != Eigen::Success) return;
    posterior.topLeftCorner(known, known) += llt.solve(LocalMatrix::Identity(known, known));
  }
  const Eigen::LLT<LocalMatrix> llt(posterior);
  if (llt.info() != Eigen::Success) return;
  posterior = llt.solve(LocalMatrix::Identity(n, n));
  if (!posterior.allFinite()) return;
  // The old bound still holds after the update: the tighter of the two.
  for (std::size_t k = 0; k < slots.size(); ++k) {
    const Eigen::Index r = 3 + 2 * static_cast<Eigen::Index>(k);
    store.setBound(slots[k], tighterBound(store.node(slots[k]).bound, posterior.block<2, 2>(r, r)));
  }
}

Mat2 firstSightingBound(const Mat3& robot_bound, const Eigen::Matrix<double, 5, 5>& information) {
  // Its only information is I: y = -I_yy^-1 I_yx x + v, Cov v = I_yy^-1, so
  // Sigma_yy = I_yy^-1 + G Sigma_xx G^T with G = I_yy^-1 I_yx.
  const Eigen::LLT<Mat2> llt(information.bottomRightCorner<2, 2>());
  if (llt.info() != Eigen::Success) {
    throw NumericError("seif: a new landmark's first observation does not fix its position (conservative covariance)");
  }
  const Mat23 G = llt.solve(information.bottomLeftCorner<2, 3>());
  return symmetric(llt.solve(Mat2::Identity()) + G * robot_bound * G.transpose());
}

Mat2 reanchoredBound(const SeifStore& store, int slot, const Vec2& to, BoundWorkspace& ws) {
  const Vec2 d = to - store.node(slot).anchor;
  const Vec2 dc(-d.y(), d.x());  // J d, as SeifStore::reanchorLandmark
  const Mat2& B = store.node(slot).bound;
  if (dc.isZero(0.0)) return B;
  // Sigma' = Cov(y + dc theta) <= (1 + e) B + (1 + 1/e) dc C_tt dc^T for any e > 0
  // ((a + b)(a + b)^T <= (1 + e) a a^T + (1 + 1/e) b b^T), and <= [dc I] C [dc I]^T over
  // (theta, y) of their joint bound C (rows and columns 2 and 3-4): the tighter.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 5, 5> C(5, 5);
  const int slots[] = {slot};
  const bool joint = conservativeCovariance(store, slots, C, ws);
  const double C_tt = joint ? C(2, 2) : conservativePoseCovariance(store, ws)(2, 2);
  const Mat2 D = C_tt * dc * dc.transpose();
  const double e = std::sqrt(D.trace() / B.trace());
  const Mat2 split = symmetric((1.0 + e) * B + (1.0 + 1.0 / e) * D);
  if (!joint) return split;
  const Mat2 C_yt = dc * C.block<2, 1>(3, 2).transpose();
  return tighterBound(symmetric(C.block<2, 2>(3, 3) + C_yt + C_yt.transpose() + D), split);
}

}  // namespace seif
