#include <seif/core/errors.hpp>
#include "core/small_llt.hpp"
#include "filters/information_ops.hpp"
#include "filters/invariant.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace seif {

Vec3 startInformation(const Vec3& initial_pose_sigma, const std::string& filter) {
  if (!(initial_pose_sigma.minCoeff() >= 1e-100)) {
    throw InvalidArgument(filter + ": an information filter needs initial_pose_sigma > 0 (its start information is "
                          "1 / sigma^2)");
  }
  return initial_pose_sigma.cwiseAbs2().cwiseInverse();
}

Mat3 invertibleMotionJacobian(const Mat3& J_delta_x) {
  const Mat3 G = Mat3::Identity() + J_delta_x;
  const double det = G.determinant();
  if (!(std::abs(det) > 1e-12)) {
    throw NumericError("motion update: the motion Jacobian I + dDelta/dx is singular (det " + std::to_string(det) + ")");
  }
  return G;
}

void informationMotionUpdate(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b,
                             Eigen::Ref<Eigen::VectorXd> mu, const Vec3& delta,
                             const Mat3& J_delta_x, const Mat3& U,
                             Eigen::Ref<Eigen::MatrixXd> workspace) {
  const Eigen::Index n = H.rows();
  // The paper's b + (Hbar - H) mu + Hbar S_x delta equals Hbar mubar + (b - H mu), and is
  // right only when mu = H^-1 b. The SEIF's amortised mean is not: the robot's row of the
  // residual r = b - H mu (non-zero after a measurement update) must be carried through
  // the motion as well, which adds  S_x (G_x^-T r_x - r_x) - Phi S_x C G_x^-T r_x.
  // The robot is linked only to variables in this block, so r_x is exact here.
  const Vec3 r_x = b.head<3>() - H.topRows<3>() * mu;
  b.noalias() -= H * mu;
  // G_x = I + dDelta/dx, any 3x3 motion Jacobian (algorithm.md §1). Its inverse by
  // cofactors: for the planar models' heading-only Jacobians this is I - dDelta/dx to the
  // last bit (unit determinant, products with 0 and 1 exact).
  const Mat3 G = invertibleMotionJacobian(J_delta_x);
  const Mat3 G_inv = G.inverse();
  // Phi = G^-T H G^-1: G^-1 differs from I only in the robot block.
  for (Eigen::Index j = 0; j < n; ++j) {
    const Vec3 col = H.col(j).head<3>();
    H.col(j).head<3>().noalias() = G_inv.transpose() * col;
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::RowVector3d row = H.row(i).head<3>();
    H.row(i).head<3>().noalias() = row * G_inv;
  }
  // kappa = Phi_{:,x} U (I + Phi_xx U)^-1 Phi_{x,:}
  const Mat3 Phi_xx = H.topLeftCorner<3, 3>();
  Mat3 C = U * (Mat3::Identity() + Phi_xx * U).partialPivLu().inverse();
  C = (0.5 * (C + C.transpose())).eval();
  auto Phi_x = workspace.topLeftCorner(3, n);
  auto C_Phi_x = workspace.block(3, 0, 3, n);
  Phi_x = H.topRows<3>();
  C_Phi_x.noalias() = C * Phi_x;
  const Vec3 s_x = G_inv.transpose() * r_x;
  b.head<3>() += s_x - r_x;
  b.noalias() -= Phi_x.transpose() * (C * s_x);
  H.noalias() -= Phi_x.transpose() * C_Phi_x;
  // Symmetric by construction up to rounding: restore it exactly.
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = j + 1; i < n; ++i) {
      const double m = 0.5 * (H(i, j) + H(j, i));
      H(i, j) = m;
      H(j, i) = m;
    }
  }
  mu.head<3>() += delta;
  b.noalias() += H * mu;
}

namespace {

/// Three rows or three columns of a local block (allocation-free).
using Rows3 = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxLocalDim>;
using Cols3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, kMaxLocalDim, 3>;

/// The gauge-keeping correction of a sparsification's change (information_ops.hpp). H0 holds
/// the block's robot rows before it; H + change is the paper's result, [C U 0] its robot rows.
/// Written as the marginal of the landmarks times the robot's conditional, that conditional's
/// residual is x - m(Y+) with
/// m(Y+) = -C^-1 U Y+; the exact one's is A z with A = H_xx^-1 [H_xx, H_xY]. Replacing U by
/// U + D with D V_+ = C H_xx^-1 (H0 V)_x - C V_x - U V_+ gives the new residual A V on the gauge
/// directions V, so V^T (Hs - H0) V = (A V)^T (C - H_xx) (A V) <= 0: the rule claims nothing
/// on them (for a gauge H0 leaves free, H0 V = 0, Hs V = 0). D is the least such change; a
/// direction V_+ cannot carry (one landmark in Y+ cannot carry a rotation) is left as the
/// paper's rule leaves it.
void keepGauge(const Rows3& H0, const Eigen::LLT<Mat3>& llt_x, LocalMatrix& change,
               const Eigen::Ref<const Eigen::MatrixXd>& gauge, Eigen::Index d) {
  const Eigen::Index n = H0.cols(), p = n - 3 - d;
  if (p < 2) return;
  // Columns made orthogonal over Y+ in their order (the translations first), so that a
  // direction Y+ cannot carry (a rotation with one landmark kept) drops out alone.
  LocalGauge V = gauge;
  std::array<bool, 3> carried{};
  for (Eigen::Index j = 0; j < V.cols(); ++j) {
    const double before = V.col(j).segment(3, p).squaredNorm();
    for (Eigen::Index i = 0; i < j; ++i) {
      if (carried[static_cast<std::size_t>(i)]) {
        V.col(j) -= V.col(i).segment(3, p).dot(V.col(j).segment(3, p)) / V.col(i).segment(3, p).squaredNorm() * V.col(i);
      }
    }
    carried[static_cast<std::size_t>(j)] = V.col(j).segment(3, p).squaredNorm() > 1e-12 * before;
  }
  const Mat3 C = H0.topLeftCorner<3, 3>() + change.topLeftCorner<3, 3>();
  const Rows3 U = H0.block(0, 3, 3, p) + change.block(0, 3, 3, p);
  const Eigen::LLT<Mat3> llt_c(C);
  if (llt_c.info() != Eigen::Success) {
    throw NumericError("sparsification: the robot's information is not positive definite");
  }
  const Rows3 HV_x = H0.topRows(3) * V;
  const Rows3 delta = C * llt_x.solve(HV_x) - C * V.topRows(3) - U * V.middleRows(3, p);
  Rows3 D = Rows3::Zero(3, p);  // D V_+ = delta on the carried columns (orthogonal: one at a time)
  for (Eigen::Index j = 0; j < V.cols(); ++j) {
    if (!carried[static_cast<std::size_t>(j)]) continue;
    const auto v = V.col(j).segment(3, p);
    D.noalias() += delta.col(j) * v.transpose() / v.squaredNorm();
  }
  const Rows3 UD = U + D;
  change.block(0, 3, 3, p) += D;
  change.block(3, 0, p, 3) += D.transpose();
  change.block(3, 3, p, p).noalias() += UD.transpose() * llt_c.solve(UD);
  change.block(3, 3, p, p).noalias() -= U.transpose() * llt_c.solve(U);
}

}  // namespace

double sparsifyInformation(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b,
                           const Eigen::Ref<const Eigen::VectorXd>& mu, int drop,
                           const Eigen::Ref<const Eigen::MatrixXd>& gauge) {
  const Eigen::Index n = H.rows();
  const Eigen::Index d = 2 * drop;        // size of Y0
  const Eigen::Index y0 = n - d;          // first row of Y0
  if (n > kMaxLocalDim || drop < 1 || y0 < 3) {
    throw NumericError("sparsification: bad block layout (" + std::to_string(n) + " rows, " +
                       std::to_string(drop) + " to deactivate)");
  }
  // Eq. (44-51) in closed form. With C = H S_x, B = H S_Y0 and W = H_Y0Y0^-1 H_Y0x, block
  // elimination of S_xY0^T H S_xY0 gives
  //   H S_xY0 (S_xY0^T H S_xY0)^-1 S_xY0^T H - H S_Y0 (S_Y0^T H S_Y0)^-1 S_Y0^T H = D S^-1 D^T
  // with D = C - B W (its Y0 rows vanish) and S = H_xx - H_xY0 W (D's robot rows), so that
  //   Hs - H = D S^-1 D^T - C H_xx^-1 C^T = E E^T - F F^T,  E = D U_S^-1, F = C U_x^-1
  // (U^T U the Cholesky factors of S and H_xx): two symmetric rank-3 updates.
  const Eigen::LLT<LocalMatrix> llt_y0(H.bottomRightCorner(d, d));
  const Eigen::LLT<Mat3> llt_x(H.topLeftCorner<3, 3>());
  if (llt_y0.info() != Eigen::Success || llt_x.info() != Eigen::Success) {
    throw NumericError("sparsification: an information block is not positive definite");
  }
  Cols3 E = H.leftCols<3>();
  E.noalias() -= H.rightCols(d) * llt_y0.solve(H.bottomLeftCorner(d, 3));  // D
  const Eigen::LLT<Mat3> llt_s(E.topRows<3>());  // S
  if (llt_s.info() != Eigen::Success) {
    throw NumericError("sparsification: an information block is not positive definite");
  }
  llt_s.matrixU().solveInPlace<Eigen::OnTheRight>(E);
  Cols3 F = H.leftCols<3>();
  llt_x.matrixU().solveInPlace<Eigen::OnTheRight>(F);
  LocalMatrix change = LocalMatrix::Zero(n, n);
  change.selfadjointView<Eigen::Lower>().rankUpdate(E, 1.0).rankUpdate(F, -1.0);
  change.triangularView<Eigen::StrictlyUpper>() = change.transpose();
  const double scale = H.cwiseAbs().maxCoeff();
  if (gauge.cols() > 0) {
    const Rows3 H0_x = H.topRows<3>();
    keepGauge(H0_x, llt_x, change, gauge, d);
  }
  H += change;
  b.noalias() += change * mu;
  return H.block(0, y0, 3, d).cwiseAbs().maxCoeff() / scale;
}

void marginalizeRobot(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b) {
  const Eigen::Index n = H.rows();
  const Eigen::Index m = n - 3;
  if (n > kMaxLocalDim || n < 3) {
    throw NumericError("robot marginalisation: bad block size (" + std::to_string(n) + " rows)");
  }
  Eigen::LLT<Mat3> llt_x(H.topLeftCorner<3, 3>());
  if (llt_x.info() != Eigen::Success) {
    throw NumericError("robot marginalisation: the robot's information is not positive definite");
  }
  // W = H_xx^-1 [H_xA, b_x]; then H_AA -= H_Ax W_A, b_A -= H_Ax W_b.
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxLocalDim> W(3, m + 1);
  W.leftCols(m) = H.topRightCorner(3, m);
  W.col(m) = b.head<3>();
  llt_x.solveInPlace(W);
  H.bottomRightCorner(m, m).noalias() -= H.bottomLeftCorner(m, 3) * W.leftCols(m);
  b.tail(m).noalias() -= H.bottomLeftCorner(m, 3) * W.col(m);
  for (Eigen::Index j = 3; j < n; ++j) {  // symmetric up to rounding: restore it exactly
    for (Eigen::Index i = j + 1; i < n; ++i) {
      const double v = 0.5 * (H(i, j) + H(j, i));
      H(i, j) = v;
      H(j, i) = v;
    }
  }
  H.topRows<3>().setZero();
  H.leftCols<3>().setZero();
  b.head<3>().setZero();
}

MeasurementInformation measurementInformation(const MeasurementModel& sensor, const Pose2& x,
                                              const Vec2& y, const Observation& z, const Mat2& Z_inv,
                                              const std::optional<Vec2>& jacobian_landmark,
                                              const std::optional<Anchors>& anchors,
                                              const std::optional<ObservabilityConstraint>& constraint) {
  Mat23 J_x;
  Mat2 J_y;
  const Vec2 zhat = sensor.predict(x, y, &J_x, &J_y);
  if (jacobian_landmark) sensor.predict(x, *jacobian_landmark, &J_x, &J_y);
  if (anchors) J_x.col(2) = invariant::anchoredHeadingColumn(J_y, anchors->robot, anchors->landmark);
  if (constraint) constraint->apply(J_x, J_y);
  Eigen::Matrix<double, 2, 5> J;
  J << J_x, J_y;
  Eigen::Matrix<double, 5, 1> mu_local;
  mu_local << x, y;
  const Vec2 nu = sensor.residual(z.z, zhat);
  const Eigen::Matrix<double, 5, 2> JtZ = J.transpose() * Z_inv;
  MeasurementInformation info;
  info.H = JtZ * J;
  info.b = JtZ * (nu + J * mu_local);
  return info;
}

namespace {

/// Where each variable sits in a blanket (-1: outside), by v + 1. The table is kept per
/// thread across queries and grows with the map; a query resets only its own entries.
class BlanketIndex {
 public:
  BlanketIndex() : pos_(table()) {}
  ~BlanketIndex() {
    for (int v : members_) pos_[static_cast<std::size_t>(v + 1)] = -1;
  }
  BlanketIndex(const BlanketIndex&) = delete;
  BlanketIndex& operator=(const BlanketIndex&) = delete;
  int find(int v) const {
    const auto k = static_cast<std::size_t>(v + 1);
    return k < pos_.size() ? pos_[k] : -1;
  }
  bool has(int v) const { return find(v) >= 0; }
  void insert(int v, int position) {
    const auto k = static_cast<std::size_t>(v + 1);
    if (k >= pos_.size()) pos_.resize(std::max(k + 1, 2 * pos_.size()), -1);
    pos_[k] = position;
    members_.push_back(v);
  }

 private:
  // Not inlined: inlined, GCC recomputes a thread_local's address (a call into the dynamic
  // linker in a shared library) at each use instead of keeping it.
  [[gnu::noinline]] static std::vector<int>& table() {
    thread_local std::vector<int> t;
    return t;
  }
  std::vector<int>& pos_;
  std::vector<int> members_;
};

/// The buffers of a local marginal query, kept per thread across queries: the blanket's
/// members, each member's links (the inner vectors keep their capacity), the frontier and
/// the dense H. No callback of a query makes another query on the same thread; take()
/// refuses one that would.
struct BlanketWorkspace {
  std::vector<int> order;
  std::vector<std::vector<BlanketLink>> links;
  std::size_t members = 0;  // links[0, members) are this query's
  std::vector<std::pair<double, int>> offered, frontier;
  std::vector<Eigen::Index> offset;
  std::vector<double> h;  // H's storage, n x n column-major
  bool busy = false;

  std::vector<BlanketLink>& nextLinks() {
    if (members == links.size()) links.emplace_back();
    std::vector<BlanketLink>& l = links[members++];
    l.clear();
    return l;
  }
};

/// This thread's workspace, emptied, for the life of the object.
class WorkspaceLease {
 public:
  WorkspaceLease() : ws_(workspace()) {
    if (ws_.busy) throw std::logic_error("localMarginalCovariance: a query inside a query on one thread");
    ws_.busy = true;
    ws_.order.clear();
    ws_.members = 0;
    ws_.frontier.clear();
  }
  ~WorkspaceLease() { ws_.busy = false; }
  WorkspaceLease(const WorkspaceLease&) = delete;
  WorkspaceLease& operator=(const WorkspaceLease&) = delete;
  BlanketWorkspace& operator*() const { return ws_; }

 private:
  [[gnu::noinline]] static BlanketWorkspace& workspace() {  // as BlanketIndex::table()
    thread_local BlanketWorkspace w;
    return w;
  }
  BlanketWorkspace& ws_;
};

}  // namespace

Eigen::MatrixXd localMarginalCovariance(std::span<const int> vars,
                                        const std::function<void(int, std::vector<BlanketLink>&)>& neighbours,
                                        const std::function<Eigen::MatrixXd(int)>& diagonal,
                                        const std::string& filter, std::size_t budget,
                                        const std::function<Eigen::MatrixXd(int)>& bound) {
  // The blanket: the queried variables first, then the others in the order they joined;
  // each member's links are kept for assembling H below.
  const WorkspaceLease lease;
  BlanketWorkspace& ws = *lease;
  std::vector<int>& order = ws.order;
  BlanketIndex index;
  const auto join = [&](int v) {
    index.insert(v, static_cast<int>(order.size()));
    order.push_back(v);
    neighbours(v, ws.nextLinks());
  };
  const auto links = [&](std::size_t a) -> const std::vector<BlanketLink>& { return ws.links[a]; };
  for (int v : vars) {
    if (!index.has(v)) join(v);
  }
  const std::size_t queried = order.size();
  if (budget == 0) {  // the Markov blanket
    for (std::size_t a = 0; a < queried; ++a) {
      for (std::size_t k = 0; k < links(a).size(); ++k) {
        const int c = links(a)[k].var;  // join() may grow ws.links: index, do not hold a reference
        if (!index.has(c)) join(c);
      }
    }
  } else {  // grown along the strongest link to the blanket so far
    // Of a member's links to variables outside, only its `room` strongest can ever be chosen,
    // room being what the budget has left (every stronger one would have to join first), so
    // only those enter the frontier (a max-heap).
    std::vector<std::pair<double, int>>& offered = ws.offered;
    std::vector<std::pair<double, int>>& frontier = ws.frontier;
    double floor = -1.0;  // links weaker than this can no longer be chosen (below)
    const auto offer = [&](std::size_t a) {
      const std::size_t room = budget - (order.size() - queried);
      offered.clear();
      for (const BlanketLink& l : links(a)) {
        if (l.strength >= floor && !index.has(l.var)) offered.emplace_back(l.strength, l.var);
      }
      if (offered.size() > room) {
        std::nth_element(offered.begin(), offered.begin() + static_cast<std::ptrdiff_t>(room), offered.end(),
                         std::greater<>());
        offered.resize(room);
      }
      // A queried member with `budget` links outside alone offers `budget` distinct variables
      // at least as strong as its weakest kept one: a floor for the members after it (below).
      if (order.size() == queried && offered.size() == budget) {
        double weakest = offered.front().first;
        for (const auto& o : offered) weakest = std::min(weakest, o.first);
        floor = std::max(floor, weakest);
      }
      for (const auto& o : offered) {
        frontier.push_back(o);
        std::push_heap(frontier.begin(), frontier.end());
      }
    };
    for (std::size_t a = 0; a < queried; ++a) offer(a);
    // When the frontier already offers `budget` distinct variables at strength >= t, the
    // heap pops all of them before anything weaker, and they fill the budget: a link weaker
    // than t is never chosen, so later members offer none (the blanket is the same).
    offered.assign(frontier.begin(), frontier.end());
    std::sort(offered.begin(), offered.end(), [](const auto& x, const auto& y) {
      return x.second != y.second ? x.second < y.second : x.first > y.first;
    });
    offered.erase(std::unique(offered.begin(), offered.end(),
                              [](const auto& x, const auto& y) { return x.second == y.second; }),
                  offered.end());  // each variable once, at its strongest
    if (offered.size() >= budget) {
      std::nth_element(offered.begin(), offered.begin() + static_cast<std::ptrdiff_t>(budget - 1), offered.end(),
                       std::greater<>());
      floor = offered[budget - 1].first;
    }
    while (order.size() - queried < budget && !frontier.empty()) {
      std::pop_heap(frontier.begin(), frontier.end());
      const int c = frontier.back().second;
      frontier.pop_back();
      if (index.has(c)) continue;
      join(c);
      if (order.size() - queried < budget) offer(order.size() - 1);
    }
  }
  // H over the blanket. Without a bound the queried variables go last: with H = L L^T their
  // marginal covariance is then (L_QQ L_QQ^T)^-1 from L's trailing block alone, the inverse of
  // the Schur complement (no solve over the whole blanket). The bound needs H^-1 E_Q on
  // every row, so there they stay first.
  const bool queried_last = !bound;
  const auto dim = [](int v) { return v < 0 ? Eigen::Index(3) : Eigen::Index(2); };
  std::vector<Eigen::Index>& offset = ws.offset;  // by member position in `order`
  offset.assign(order.size(), 0);
  Eigen::Index next = 0, q = 0;
  for (std::size_t a = 0; a < queried; ++a) q += dim(order[a]);
  for (std::size_t a = queried_last ? queried : 0; a < order.size(); ++a) {
    offset[a] = next;
    next += dim(order[a]);
  }
  for (std::size_t a = 0; queried_last && a < queried; ++a) {
    offset[a] = next;
    next += dim(order[a]);
  }
  // Only its lower triangle is assembled (and zeroed): the Cholesky factorisation and the
  // solves with its factor read no other (small_llt.hpp). A link's block lies wholly on one
  // side of the diagonal.
  const Eigen::Index n = next;
  ws.h.resize(static_cast<std::size_t>(n * n));
  Eigen::Map<Eigen::MatrixXd> H(ws.h.data(), n, n);
  for (Eigen::Index j = 0; j < n; ++j) H.col(j).tail(n - j).setZero();
  for (std::size_t a = 0; a < order.size(); ++a) {
    const Eigen::Index da = dim(order[a]);
    H.block(offset[a], offset[a], da, da) = diagonal(order[a]);
    for (const BlanketLink& l : links(a)) {
      if (l.block == nullptr) continue;  // written from the other side
      const int found = index.find(l.var);
      if (found < 0) continue;
      const auto c = static_cast<std::size_t>(found);
      const Eigen::Index dc = dim(l.var);
      const Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> B(l.block, da, dc, Eigen::OuterStride<>(l.stride));
      if (offset[c] > offset[a]) {
        H.block(offset[c], offset[a], dc, da) = B.transpose();
      } else {
        H.block(offset[a], offset[c], da, dc) = B;
      }
    }
  }
  const auto indefinite = [&] {
    return NumericError(filter + ": the information of a Markov blanket is not positive definite");
  };
  if (queried_last) {
    if (!choleskyInPlace(H)) throw indefinite();
    // Sigma_QQ = (L_QQ L_QQ^T)^-1 = L_QQ^-T L_QQ^-1, L_QQ the trailing q x q block.
    Eigen::MatrixXd Linv = Eigen::MatrixXd::Identity(q, q);
    H.bottomRightCorner(q, q).triangularView<Eigen::Lower>().solveInPlace(Linv);
    Eigen::MatrixXd blanket(q, q);
    blanket.noalias() = Linv.transpose() * Linv;
    // In the order asked: the queried lead `order` and sit at offset - (n - q) in the block.
    std::vector<Eigen::Index> rows;
    rows.reserve(static_cast<std::size_t>(q));
    for (int v : vars) {
      const Eigen::Index at = offset[static_cast<std::size_t>(index.find(v))] - (n - q);
      for (Eigen::Index i = 0; i < dim(v); ++i) rows.push_back(at + i);
    }
    return blanket(rows, rows);
  }
  const SmallLLT<Eigen::MatrixXd> llt(H);
  if (llt.info() != Eigen::Success) throw indefinite();
  // Only the queried variables' columns, in the order asked (they lead the blanket).
  const Eigen::MatrixXd Z = llt.solve(Eigen::MatrixXd::Identity(H.rows(), q));  // H_II^-1 E_Q
  Eigen::MatrixXd X = Z.topRows(q);
  {
    // The boundary's share: y_I = -H_II^-1 H_Ib y_b + v, v independent of the rest, so
    // Sigma_QQ = X + sum over boundary pairs M_c Cov(y_c, y_d) M_d^T, M_c = -Z^T H_Ic, which
    // covariance intersection bounds by sum_c M_c B_c M_c^T / w_c (seif_bounds.hpp).
    std::unordered_map<int, std::size_t> at;  // boundary variable -> its M_c
    std::vector<std::pair<int, Eigen::MatrixXd>> M;
    std::unordered_map<int, std::vector<BlanketLink>> far_links;  // of boundary variables, when needed
    for (std::size_t a = 0; a < order.size(); ++a) {
      const Eigen::Index da = dim(order[a]);
      for (const BlanketLink& l : links(a)) {
        if (index.has(l.var)) continue;
        const Eigen::Index dc = dim(l.var);
        Eigen::MatrixXd H_ac(da, dc);
        if (l.block != nullptr) {
          H_ac = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(l.block, da, dc, Eigen::OuterStride<>(l.stride));
        } else {  // given from the boundary variable's side, as H_{c,a}
          auto [it, fresh] = far_links.try_emplace(l.var);
          if (fresh) neighbours(l.var, it->second);
          const auto back = std::find_if(it->second.begin(), it->second.end(),
                                         [&](const BlanketLink& b) { return b.var == order[a] && b.block != nullptr; });
          if (back == it->second.end()) throw NumericError(filter + ": a link without its block");
          H_ac = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(back->block, dc, da,
                                                                            Eigen::OuterStride<>(back->stride))
                     .transpose();
        }
        auto [it, fresh] = at.try_emplace(l.var, M.size());
        if (fresh) M.emplace_back(l.var, Eigen::MatrixXd::Zero(q, dc));
        M[it->second].second.noalias() -= Z.middleRows(offset[a], da).transpose() * H_ac;
      }
    }
    std::vector<double> traces(M.size());
    std::vector<Eigen::MatrixXd> bounds(M.size());
    double total = 0.0;
    for (std::size_t c = 0; c < M.size(); ++c) {
      bounds[c] = bound(M[c].first);
      traces[c] = (M[c].second * bounds[c] * M[c].second.transpose()).trace();
      total += std::sqrt(traces[c]);
    }
    for (std::size_t c = 0; c < M.size(); ++c) {
      if (traces[c] > 0.0) X.noalias() += (total / std::sqrt(traces[c])) * M[c].second * bounds[c] * M[c].second.transpose();
    }
  }
  std::vector<Eigen::Index> rows;
  rows.reserve(static_cast<std::size_t>(q));
  for (int v : vars) {
    const Eigen::Index at = offset[static_cast<std::size_t>(index.find(v))];
    for (Eigen::Index i = 0; i < dim(v); ++i) rows.push_back(at + i);
  }
  return X(rows, rows);
}

FilterStats denseLinkStats(const Eigen::MatrixXd& H) {
  FilterStats s;
  const int landmarks = static_cast<int>((H.rows() - 3) / 2);
  s.landmarks = static_cast<std::size_t>(landmarks);
  auto offset = [](int v) { return v == 0 ? 0 : 3 + 2 * (v - 1); };
  auto size = [](int v) { return v == 0 ? 3 : 2; };
  std::vector<std::size_t> degree(static_cast<std::size_t>(landmarks) + 1, 0);
  for (int i = 0; i <= landmarks; ++i) {
    for (int j = i + 1; j <= landmarks; ++j) {
      if (H.block(offset(i), offset(j), size(i), size(j)).cwiseAbs().maxCoeff() > 0.0) {
        ++s.links;
        ++degree[static_cast<std::size_t>(i)];
        ++degree[static_cast<std::size_t>(j)];
      }
    }
  }
  s.robot_links = degree[0];
  for (int i = 1; i <= landmarks; ++i) {
    s.max_landmark_links = std::max(s.max_landmark_links, degree[static_cast<std::size_t>(i)]);
  }
  const std::size_t vars = static_cast<std::size_t>(landmarks) + 1;
  s.blocks_touched = vars * vars;
  return s;
}

double overclaimRatio(const Eigen::Ref<const Eigen::MatrixXd>& E, const Eigen::Ref<const Eigen::MatrixXd>& Sigma) {
  // v^T E v <= c v^T Sigma^-1 v for all v  <=>  w^T (L^T E L) w <= c w^T w with v = L^-T w.
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (Sigma + Sigma.transpose()));
  if (llt.info() != Eigen::Success) throw NumericError("conservative sparsification: the block's covariance is not positive definite");
  const Eigen::MatrixXd L = llt.matrixL();
  const Eigen::MatrixXd M = L.transpose() * E * L;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (M + M.transpose()), Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) throw NumericError("conservative sparsification: no eigenvalues");
  return std::max(0.0, eig.eigenvalues().maxCoeff());
}

}  // namespace seif
