#pragma once
// The SEIF's options (filter specs "seif:key=value,...", filters/factory.hpp): how many
// landmarks stay active, how the mean is recovered, how the robot's links are bounded.
#include <cstdint>
#include <string_view>

namespace seif {

struct SeifOptions {
  enum class Mean { Amortized, Exact };
  enum class Deactivate { Weakest, Oldest };
  enum class Recovery { AfterMeasurement, BeforeMeasurement };
  enum class RelaxOrder { Random, Cyclic, Wildfire };
  enum class Sparsify { Seif, Eseif, Conservative };
  enum class Covariance { Exact, Local, Conservative };
  enum class Motion { Immediate, Deferred };
  enum class Gauge { Paper, Kept };
  enum class Coarse { Off, Rigid };

  int active = 6;  ///< theta_x (the paper's name): landmarks linked to the robot after each step
  int relax = 10;      ///< K: landmarks relaxed per step besides the robot and the active ones
                       ///< (at most every landmark once: K is capped at the map size)
  /// Amortized: constant-time coordinate descent. Exact: sparse Cholesky solve of H mu = b
  /// after every update ("SEIF with exact mu" in the paper's table; not constant time).
  Mean mean = Mean::Amortized;
  /// The amortised mean's over-relaxation, in (0, 2): each of the K relaxed landmarks moves
  /// omega times its Gauss-Seidel step, mu_i <- mu_i + omega (eq. 42 - mu_i) (successive
  /// over-relaxation). 1: eq. (42) as published. Gauss-Seidel removes the smooth part of the
  /// mean's error - a map bent by a loop closure - at the rate of H's slowest modes; over-
  /// relaxation near 2 removes it many times faster at the same cost (docs/consistency.md,
  /// "The mean's over-relaxation"). Each step still lowers 1/2 mu^T H mu - b^T mu for any omega in (0, 2).
  double omega = 1.0;
  /// Weakest: deactivate the landmarks with the weakest normalised link to the robot (the
  /// paper). Oldest: those observed least recently.
  Deactivate deactivate = Deactivate::Weakest;
  /// Stale first: a surplus is taken first from the active landmarks not observed in the last
  /// `stale` steps, the longest unobserved first; `deactivate` orders the rest. 0: off. The
  /// weakest-link rule can keep a landmark active long after it was last seen and then
  /// condition the robot on it during a loop closure (docs/consistency.md, "Victoria Park:
  /// where the profile's map goes wrong": 400 steps, 9 s there).
  long stale = 0;
  /// When the amortised mean is relaxed within update(): BeforeMeasurement (default) is the
  /// book's order (Probabilistic Robotics Table 12.1): the measurement update linearises at
  /// a freshly relaxed mean. AfterMeasurement lets the sparsification and the next motion
  /// update use a mean that already contains the newest measurements. docs/seif.md compares them.
  Recovery recovery = Recovery::BeforeMeasurement;
  /// Which K landmarks each step relaxes: the next K in map order, Cyclic (default: each
  /// landmark at the same rate, and neighbours in the map tend to be neighbours in memory,
  /// so a huge map's cache misses stay down), or drawn uniformly at Random (the paper; `seif
  /// paper` uses it). Equally accurate on the paper's world; docs/seif.md has the numbers.
  /// Wildfire: first the neighbours of landmarks whose mean has moved by more than
  /// `wildfire` of its conditional standard deviation, in the order they were queued, then
  /// the cyclic order (src/filters/seif_relax_frontier.hpp; docs/consistency.md, "The
  /// wildfire order").
  RelaxOrder relax_order = RelaxOrder::Cyclic;
  /// RelaxOrder::Wildfire: the move, in conditional standard deviations
  /// ((mu_i - r_i)^T H_ii (mu_i - r_i) > wildfire^2), that queues a landmark's neighbours.
  double wildfire = 0.05;
  std::uint64_t seed = 1;  ///< for the random choice of relaxed landmarks
  /// How the robot's links are kept at `active`: Seif conditions the surplus away (paper
  /// eq. 44-51; overconfident, Eustice et al. 2005). Eseif marginalises the robot out and
  /// relocalises it from part of the current measurements (Walter, Eustice, Leonard 2007):
  /// H stays exactly sparse and nothing is conditioned away. Conservative: the paper's rule,
  /// then H and b scaled by 1 / (1 + c) with the least c for which the result claims no
  /// more than H did over the sparsified block's blanket (docs/consistency.md,
  /// "Conservative sparsification"): the mean is kept, the covariance inflated; O(1).
  Sparsify sparsify = Sparsify::Seif;
  /// How poseCovariance() and landmarkCovariance() are recovered. Exact: from the sparse
  /// Cholesky factor of H and its selected inverse, one factorisation per changed H (O(N)
  /// at the paper's sparsity, cached: every marginal of one state costs it once). Local: the
  /// inverse of H restricted to a blanket around the variable (`blanket`), O(1): it
  /// conditions on everything outside, so it is never larger than the marginal.
  /// Conservative: the upper bound MarginalMode::Conservative keeps, O(1), never smaller
  /// (turns `bounds` on).
  Covariance covariance = Covariance::Exact;
  /// Keep an upper bound on every landmark's marginal covariance, for MarginalMode::
  /// Conservative (gates that must not reject the right landmark; docs/consistency.md).
  /// Constant time, but it scans the links of the robot's block every update: about 2.4x the
  /// paper SEIF's step on Victoria Park (8 -> 19 us), 2.9x the consistent profile's.
  bool bounds = false;
  /// The blanket of a local marginal (MarginalMode::Local, Covariance::Local): at most this
  /// many variables besides the queried ones, grown from them along the strongest links
  /// (normalised, at any distance). 0: the whole Markov blanket, which is not bounded (a
  /// landmark of Victoria Park carries up to 189 links). A larger blanket conditions on less
  /// and comes closer to the marginal; docs/association.md measures it against the exact one.
  int blanket = 32;
  /// Eseif: how many landmarks' observations relocalise the robot (z_beta), best informed
  /// first: >= 2 (a 2-D point sensor's least for the 3-dof pose), more while the pose is
  /// ill-conditioned, never more than `active`. A step with fewer mapped landmarks in view
  /// does not relocalise (the odometry is kept; the active set waits for a step that can):
  /// relocalising from fewer threw the odometry away for a poor pose (MRCLAM). More give a
  /// better relocalised pose (docs: the paper's world's map error is several times smaller
  /// with 4 than with 2).
  int beta = 4;
  /// Linearization::Invariant: an observed landmark whose mean has moved more than this
  /// [m] from where H is anchored for it is re-anchored before its update (its neighbours
  /// then link to the robot's heading; algorithm.md, "per-landmark anchors"). 0 re-anchors
  /// at every observation. The robot is re-anchored at every update.
  double reanchor = 0.005;
  /// When a motion increment enters H. Immediate: at every predict() (the paper's §1).
  /// Deferred: the increments between two observations are composed into one (x' = x +
  /// Delta_1 + Delta_2, G = G_2 G_1, U = G_2 U_1 G_2^T + U_2) that enters H when the next
  /// non-empty update() (or a query of the robot's information) needs it; an update without
  /// observations only relaxes `relax` landmarks of the map, whose posterior the robot's
  /// motion does not change. The same information in exact arithmetic (each increment
  /// linearised at the same predicted pose), for one motion update per observation instead of
  /// one per control: on Victoria Park (40 Hz odometry, 9 % of the steps with a laser scan)
  /// docs/seif.md measures it.
  Motion motion = Motion::Immediate;
  /// The journal paper's knob (IJRR 2004, §5.3: H <- (1 - rho) H + rho H0, here H0 = 0): at each
  /// sparsification H and b are scaled by 1 - rho, the mean kept and the covariance inflated by
  /// 1 / (1 - rho); O(1) (SeifSlam::informationScale()). In [0, 1); 0: off. Not with Eseif.
  double rho = 0.0;
  /// What a sparsification (Seif, Conservative) does to the directions the posterior leaves
  /// free - the map and robot translated or rotated together, at the anchors of the invariant
  /// linearisation or at the means. Paper: eq. (44-51) as published; it holds the deactivated
  /// landmarks fixed in the world and so claims information on them (4 orders of magnitude
  /// more than the prior on the translation on the paper's world). Kept: the robot's new
  /// links to the landmarks it keeps are corrected so that the result claims none
  /// (docs/consistency.md, "The gauge"); O(1).
  Gauge gauge = Gauge::Paper;
  /// The amortised mean's coarse level. Off: Gauss-Seidel alone (eq. 42), whose error
  /// along the map's rigid motions decays slowly (the map lags its posterior as a whole).
  /// Rigid: after each relaxation, the Galerkin correction over the rigid motions of robot
  /// and map, alpha = (V^T H V)^-1 V^T (b - H mu), kept in O(1) per step
  /// (docs/consistency.md, "The mean's coarse level"). Unused with Mean::Exact.
  Coarse coarse = Coarse::Off;

  static Mean parseMean(std::string_view s);              ///< "amortized" | "exact"
  static Deactivate parseDeactivate(std::string_view s);  ///< "weakest" | "oldest"
  static Recovery parseRecovery(std::string_view s);      ///< "after-update" | "before-update"
  static RelaxOrder parseRelaxOrder(std::string_view s);  ///< "random" | "cyclic" | "wildfire"
  static Sparsify parseSparsify(std::string_view s);      ///< "seif" | "eseif" | "conservative"
  static Covariance parseCovariance(std::string_view s);  ///< "exact" | "local" | "conservative"
  static Motion parseMotion(std::string_view s);          ///< "immediate" | "deferred"
  static Gauge parseGauge(std::string_view s);            ///< "paper" | "kept"
  static Coarse parseCoarse(std::string_view s);          ///< "off" | "rigid"
};

/// The name parse*() takes for each value, as specs, flags and metrics.json spell it.
std::string_view optionName(SeifOptions::Mean v);
std::string_view optionName(SeifOptions::Deactivate v);
std::string_view optionName(SeifOptions::Recovery v);
std::string_view optionName(SeifOptions::RelaxOrder v);
std::string_view optionName(SeifOptions::Sparsify v);
std::string_view optionName(SeifOptions::Covariance v);
std::string_view optionName(SeifOptions::Motion v);
std::string_view optionName(SeifOptions::Gauge v);
std::string_view optionName(SeifOptions::Coarse v);

}  // namespace seif
