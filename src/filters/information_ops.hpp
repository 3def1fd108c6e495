#pragma once
// The information-form steps shared by the EIF (on its whole matrix) and the SEIF (on the
// small dense block it gathers around the robot). One implementation of each equation.
#include <seif/core/types.hpp>
#include "filters/first_estimates.hpp"
#include <seif/models/measurement_model.hpp>

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace seif {

/// G = I + J_delta_x, throwing NumericError when it is singular (det within 1e-12 of 0): the
/// motion update inverts it. Deferred motion checks each increment with it as it comes.
Mat3 invertibleMotionJacobian(const Mat3& J_delta_x);

/// The start's information 1 / initial_pose_sigma^2 of an information filter (EIF, SEIF).
/// Throws InvalidArgument for a zero sigma, whose information is not finite.
Vec3 startInformation(const Vec3& initial_pose_sigma, const std::string& filter);

/// Motion update in information form, paper Lemma 3 / algorithm.md §1, on a dense
/// symmetric matrix whose first three rows and columns are the robot pose:
///   Phi = G^-T H G^-1,  kappa = Phi S_x (U^-1 + S_x^T Phi S_x)^-1 S_x^T Phi,
///   H <- Phi - kappa,   b <- b + (Hbar - H) mu + Hbar S_x delta,   mu <- mu + S_x delta.
/// (U^-1 + A)^-1 is evaluated as U (I + A U)^-1, so a singular U (the two-dimensional
/// velocity noise) is fine. G = I + J_delta_x is any invertible 3x3 Jacobian (NumericError
/// when singular). Exact when H holds every variable linked to the robot.
/// The paper's b update assumes mu = H^-1 b; here the residual b - H mu of the robot's row
/// is carried through the motion too, so the result is exact (for the model linearised at
/// mu) whatever mean is supplied - the SEIF's amortised mean is not exact.
/// `workspace` needs at least 6 rows and H.cols() columns; with it the update allocates
/// nothing (the SEIF calls it on a small stack block every step).
void informationMotionUpdate(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b,
                             Eigen::Ref<Eigen::VectorXd> mu, const Vec3& delta,
                             const Mat3& J_delta_x, const Mat3& U,
                             Eigen::Ref<Eigen::MatrixXd> workspace);

/// Largest block the SEIF gathers: the robot and up to kMaxLocalLandmarks landmarks.
inline constexpr int kMaxLocalLandmarks = 40;
inline constexpr int kMaxLocalDim = 3 + 2 * kMaxLocalLandmarks;
using LocalMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                                  kMaxLocalDim, kMaxLocalDim>;
using LocalVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxLocalDim, 1>;

/// Sparsification, paper eq. (44-51) / algorithm.md §4, on the dense block of the robot and
/// its active landmarks ordered [x (3), Y+ (2 each), Y0 (2 each)] with `drop` landmarks in
/// Y0 (the last ones). H0 is this block (conditioning on the passive Y- = 0):
///   Hs = H - H0 S_Y0 (S_Y0^T H0 S_Y0)^-1 S_Y0^T H0 + H0 S_xY0 (S_xY0^T H0 S_xY0)^-1 S_xY0^T H0
///          - H S_x (S_x^T H S_x)^-1 S_x^T H,            bs = b + (Hs - H) mu.
/// Returns the largest magnitude the formula left in the robot-Y0 blocks (zero up to
/// rounding; the caller removes those links), relative to the largest entry of the block.
/// At most kMaxLocalDim rows; allocates nothing. Throws NumericError if a block is singular.
/// With `gauge` (the block's rows of the directions the posterior leaves free: translations,
/// rotation; columns), the robot's new links to Y+ are corrected so that the result claims no
/// information along them that H did not hold (docs/consistency.md, "The gauge").
double sparsifyInformation(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b,
                           const Eigen::Ref<const Eigen::VectorXd>& mu, int drop,
                           const Eigen::Ref<const Eigen::MatrixXd>& gauge = Eigen::MatrixXd());
using LocalGauge = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxLocalDim, 3>;

/// The least c >= 0 with E <= c Sigma^-1 in the Loewner order: the largest eigenvalue of
/// L^T E L (Sigma = L L^T), or 0 when E claims nothing. For E = H~ - H, the change a
/// sparsification made to a block whose marginal covariance is Sigma, (H + E) / (1 + c) <= H
/// (docs/consistency.md, "Conservative sparsification"). Throws NumericError unless Sigma is
/// positive definite.
double overclaimRatio(const Eigen::Ref<const Eigen::MatrixXd>& E, const Eigen::Ref<const Eigen::MatrixXd>& Sigma);

/// ESEIF sparsification, its marginalisation (Walter, Eustice, Leonard 2007), on a dense
/// block whose first three rows are the robot and which holds its whole Markov blanket
/// (every variable linked to it): the Schur complement over the robot
///   H_AA <- H_AA - H_Ax H_xx^-1 H_xA,   b_A <- b_A - H_Ax H_xx^-1 b_x,
/// after which the robot's rows, columns and b entries are zero. The other variables'
/// marginal is unchanged. At most kMaxLocalDim rows; allocates nothing. Throws NumericError
/// if H_xx is not positive definite.
void marginalizeRobot(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b);

/// Information added by one observation, paper eq. (21-22), ordered [robot (3),
/// landmark (2)]:  dH = J^T Z^-1 J,  db = J^T Z^-1 (z - zhat + J mu), linearised at the
/// robot mean x and landmark mean y; z - zhat is the sensor's residual (bearing wrapped).
/// With `jacobian_landmark` (first-estimates Jacobians, Huang et al. 2010, the FEJ-EKF) J is
/// evaluated at (x, jacobian_landmark) instead, while zhat = h(x, y) and the mean in
/// J mu stay the current ones: db = J^T Z^-1 (z - h(x, y) + J [x; y]).
/// With `anchors` (Linearization::Invariant) J_x's heading column is the lever arm at the
/// positions H is anchored at, -J_y J (a_l - a_p) (invariant.hpp), not at (x, y).
struct MeasurementInformation {
  Eigen::Matrix<double, 5, 5> H;
  Eigen::Matrix<double, 5, 1> b;
};
struct Anchors {
  Vec2 robot;
  Vec2 landmark;
};
MeasurementInformation measurementInformation(const MeasurementModel& sensor, const Pose2& x,
                                              const Vec2& y, const Observation& z, const Mat2& Z_inv,
                                              const std::optional<Vec2>& jacobian_landmark = std::nullopt,
                                              const std::optional<Anchors>& anchors = std::nullopt,
                                              const std::optional<ObservabilityConstraint>& constraint = std::nullopt);

/// A variable linked to another in H (-1 the robot, else a landmark slot) and the link's
/// strength: the squared norm of the block on the normalised information matrix,
/// ||D_a^-1/2 H_ac D_c^-1/2||_F^2 with D the diagonals of H_aa and H_cc (the partial
/// correlation the link carries; the paper's sparsification ranks the robot's links the same way).
struct BlanketLink {
  int var = 0;
  double strength = 0.0;
  /// H_{v,var} (dim v x dim var, column-major, columns `stride` apart), or nullptr when the
  /// link is read from var's side (as H_{var,v}).
  const double* block = nullptr;
  Eigen::Index stride = 0;
};

/// The strength of a link H_ac between variables whose information diagonals are da and dc.
template <class Block, class DiagA, class DiagC>
double linkStrength(const DiagA& da, const Block& H_ac, const DiagC& dc) {
  double s = 0.0;
  for (Eigen::Index i = 0; i < H_ac.rows(); ++i) {
    for (Eigen::Index j = 0; j < H_ac.cols(); ++j) s += H_ac(i, j) * H_ac(i, j) / (da(i) * dc(j));
  }
  return s;
}

/// linkStrength of a 2x2 block between two landmarks, given column-major: its four
/// quotients divided two at a time (one column per packed division) and summed in
/// linkStrength's order, so the value is the same to the bit (IEEE division and products
/// are correctly rounded whether packed or not). The division is most of a link's cost in
/// a blanket query.
inline double linkStrength2(const Vec2& da, const double* H_ac, const Vec2& dc) {
  const Eigen::Array2d c0 = Eigen::Map<const Eigen::Array2d>(H_ac).square() / (da.array() * dc(0));
  const Eigen::Array2d c1 = Eigen::Map<const Eigen::Array2d>(H_ac + 2).square() / (da.array() * dc(1));
  return ((c0(0) + c1(0)) + c0(1)) + c1(1);  // (0,0), (0,1), (1,0), (1,1): row by row
}

/// The Local marginal (SlamFilter::marginal, MarginalMode::Local): the joint covariance of
/// `vars` (-1 the robot, else landmark slots; in that order in the result) read off the
/// inverse of H restricted to them and a blanket around them. `neighbours(v, out)` appends
/// the variables linked to v with their strengths and blocks (each link's block given by at
/// least one side); `diagonal(v)` is H_{v,v} (3x3 for the robot, else 2x2).
/// - budget 0: the blanket is the Markov blanket, every variable linked to a queried one.
/// - budget b > 0: the blanket grows from the queried variables one variable at a time, the
///   one with the strongest link to those already in, at any distance, until it holds b
///   variables besides the queried ones. The blankets of growing budgets are nested, so the
///   result grows with b (conditioning on less) towards the exact marginal.
/// With `bound` (an upper bound on any variable's marginal covariance) the result is
/// MarginalMode::Conservative instead: the same plus the share of the variables just outside
/// the blanket, y_I = -H_II^-1 H_Ib y_b + v, with Cov(y_b) bounded by covariance intersection
/// of their bounds (seif_bounds.hpp), so never smaller than the marginal; it shrinks towards
/// the marginal as the blanket grows, as the local one grows towards it.
/// O(s^3) for s variables in the blanket. Throws NumericError when the restricted
/// information is not positive definite.
Eigen::MatrixXd localMarginalCovariance(std::span<const int> vars,
                                        const std::function<void(int, std::vector<BlanketLink>&)>& neighbours,
                                        const std::function<Eigen::MatrixXd(int)>& diagonal,
                                        const std::string& filter, std::size_t budget = 0,
                                        const std::function<Eigen::MatrixXd(int)>& bound = {});

/// Counts the links of a dense information matrix in the state order [robot, landmarks]:
/// non-zero off-diagonal blocks, the robot's links and the largest landmark degree.
struct FilterStats;
FilterStats denseLinkStats(const Eigen::MatrixXd& H);

}  // namespace seif
