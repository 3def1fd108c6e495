#pragma once
// The SEIF's block-sparse store of the information matrix H, the information vector b and
// the mean mu (Thrun et al. 2002, §3; algorithm.md): the robot's 3x3 block, per landmark its
// 2x2 block and its links to other landmarks, and the robot's links to the active landmarks.
// The filter's steps work on a small dense block gathered from it (the robot and listed
// landmarks, at most kMaxLocalLandmarks) and scattered back; the amortised mean relaxes one
// variable at a time on it (eq. 42). Only new landmarks and new links allocate.
#include "filters/fixed_part_solver.hpp"
#include "filters/information_ops.hpp"
#include "filters/landmark_book.hpp"
#include "filters/seif_links.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/SparseCore>
#include <cstddef>
#include <span>
#include <vector>

namespace seif {

class SeifStore {
 public:
  using LinkBlock = LinkList::Block;
  using Link = LinkList::Ref;  // {slot, H_{this, other}}, what iterating a node's links yields
  struct RobotLink {
    int slot;
    Mat32 H;         // H_{x, landmark}
    long last_seen;  // step() of its last observation
  };
  // The fields are ordered by when they are read. The first 48 bytes hold what a neighbour's
  // visit reads (mu, ref: mean() is mu plus the frame offset at ref; active); with
  // H and what relaxing the node itself adds (b, links) they fill the first 144, and with the
  // coarse level's row (relaxLandmark() reads it with SeifOptions::coarse) the first 192;
  // the bound, used only with SeifOptions::bounds, comes last.
  struct Node {
    Vec2 mu = Vec2::Zero();
    // The mean's coarse level (enableCoarse(); seif_store_coarse.cpp): where its rigid
    // motions are taken (its mean when it entered).
    Vec2 ref = Vec2::Zero();
    int active = -1;  // position in robotLinks(), or -1 when passive
    long mean_journaled = -1;  // the transaction that saved its mean last
    Mat2 H = Mat2::Zero();
    Vec2 b = Vec2::Zero();
    LinkList links;
    // The coarse level's row of H V without the robot term, and whether that row is out of
    // the sums until settleCoarse().
    Mat23 w = Mat23::Zero();
    bool coarse_dirty = false;
    long journaled = -1;  // the transaction that saved it whole last (beginTransaction())
    /// Where H is anchored for this landmark (Linearization::Invariant; src/filters/invariant.hpp):
    /// its mean when it entered or was last re-anchored.
    Vec2 anchor = Vec2::Zero();
    /// An upper bound (Loewner order) on its marginal covariance under H, kept by the filter
    /// (seif_bounds.hpp: MarginalMode::Conservative); zero until its first sighting sets it.
    Mat2 bound = Mat2::Zero();
  };

  /// A map without landmarks: the robot's information H_xx at mean mu_x (b_x = H_xx mu_x).
  SeifStore(const Mat3& H_xx, const Vec3& mu_x);

  // ---- reading
  int size() const { return static_cast<int>(nodes_.size()); }
  /// Landmark ids by slot (for messages; LandmarkBook maps ids to slots).
  const std::vector<int>& ids() const { return ids_; }
  const Mat3& robotInformation() const { return H_xx_; }
  const Vec3& robotVector() const { return b_x_; }
  const Vec3& robotMean() const { return mu_x_; }
  const Node& node(int slot) const { return nodes_[static_cast<std::size_t>(slot)]; }
  /// Landmark `slot`'s mean: Node::mu, plus the map's rigid correction when the coarse level
  /// is on (Node::mu then holds the mean before the corrections since it was last written).
  Vec2 mean(int slot) const {
    const Node& n = node(slot);
    return coarse_ ? Vec2(n.mu + frameOffset(n.ref)) : n.mu;
  }
  /// The active landmarks, in no particular order (removeRobotLink() swaps in the last).
  const std::vector<RobotLink>& robotLinks() const { return robot_links_; }
  /// H_{a,c} of two landmark slots, or nullptr when they are not linked.
  const LinkBlock* findLink(int a, int c) const;
  /// H as a sparse matrix, b and mu, in the state order [x, y, th, landmarks...].
  Eigen::SparseMatrix<double> sparseInformation() const;
  /// Its lower triangle (what a sparse Cholesky factorisation reads), built in place in
  /// compressed columns without triplets: the one copy of H a factorisation needs.
  Eigen::SparseMatrix<double> lowerInformation() const;
  Eigen::VectorXd informationVector() const;
  Eigen::VectorXd mean() const;

  // ---- steps and counters
  /// Starts a filter step: counts it (RobotLink::last_seen, error messages) and zeroes
  /// blocksTouched().
  void beginStep() {
    ++step_;
    blocks_touched_ = 0;
  }
  long step() const { return step_; }
  /// H blocks read or written since beginStep().
  std::size_t blocksTouched() const { return blocks_touched_; }
  /// O(1): landmarks, robot links, links (robot + landmark pairs), most links any landmark
  /// has had, blocks touched.
  FilterStats stats() const;

  // ---- writing
  /// Adds landmark `id` as the next slot, without information, at mean mu; its slot.
  int addLandmark(int id, const Vec2& mu);
  /// Adds one observation's information over [robot (3), landmark `slot` (2)] (eq. 21-22),
  /// linking the landmark to the robot (activating it) and marking it seen at step().
  void addObservation(int slot, const Eigen::Matrix<double, 5, 5>& H,
                      const Eigen::Matrix<double, 5, 1>& b);
  /// H_{a,c} += H_ac and H_{c,a} += H_ac^T, creating the link if needed.
  void addToLink(int a, int c, const Mat2& H_ac);
  /// Deactivates landmark `slot`: drops its robot link (the last one takes its place).
  void removeRobotLink(int slot);
  /// ESEIF relocalisation's start (Walter et al. 2007): the robot, already marginalised out
  /// (its information and links zero, e.g. a scattered marginalizeRobot() block), restarts
  /// without information at mean mu_x: every robot link is dropped, H_xx = 0, b_x = 0.
  /// addObservation() then gives it its new information.
  void detachRobot(const Vec3& mu_x);
  /// Marginalises landmark `slot` out exactly (the Schur complement over it, on its Markov
  /// blanket): for neighbours a, c of it (the robot when it is active, its linked landmarks)
  ///   H_ac -= H_al H_ll^-1 H_lc,   b_a -= H_al H_ll^-1 b_l,
  /// linking its neighbours to each other (a landmark linked to it becomes active when it was
  /// linked to the robot too); then deleteLandmark(slot). O(d^2) for d neighbours. Throws
  /// NumericError when H_ll is not positive definite.
  void marginalizeLandmark(int slot);
  /// Merges landmark `drop` into `keep` (two slots of one landmark): the posterior on
  /// y_keep = y_drop, H' = T^T H T and b' = T^T b with T copying y_keep into y_drop's place:
  /// drop's blocks, links and robot link are added into keep's; then deleteLandmark(drop).
  /// keep's mean is left for the mean recovery. O(d) for d links.
  void mergeLandmarks(int keep, int drop);
  /// Deletes landmark `slot` and every link to it (no information moves: the callers above
  /// first move it); the last slot takes its place (its neighbours' links and robot link
  /// follow it). O(d) for the d links of the two.
  void deleteLandmark(int slot);
  /// Sets the whole mean, in the state order.
  void setMean(const Eigen::VectorXd& mu);
  /// Sets landmark `slot`'s covariance bound (Node::bound).
  void setBound(int slot, const Mat2& bound) { write(slot).bound = bound; }

  // ---- the mean's coarse level (seif_store_coarse.cpp; SeifOptions::coarse)
  // A two-level relaxation: Gauss-Seidel (above) corrects the mean where H changed, but the
  // smooth error it leaves, the map moved or turned against the posterior, decays slowly.
  // The coarse level corrects it over V, the rigid motions of robot and map (rows
  // V_i = [I, J (ref_i - o)] per landmark, [I, J (mu_p - o); 0 0 1] for the robot), by the
  // Galerkin step alpha = (V^T H V)^-1 V^T (b - H mu), mu += V alpha. Both sums are kept in
  // O(1) per change: g = sum_i (V_i^T b_i - w_i^T mu_i) and A = sum_i V_i^T w_i with
  // w_i = (H V)_i without its robot term, each term a landmark's own; the robot's row and
  // the active landmarks' robot terms, which move with V_x, are added fresh (O(active)).
  // The map's share of V alpha is held as one frame offset (mean()), not written into every
  // landmark.
  /// Turns the coarse level on (an empty map, or sums recomputed: O(N)).
  void enableCoarse();
  bool coarse() const { return coarse_; }
  /// The Galerkin step on the rigid motions (above). O(active + changed rows). False (and
  /// nothing changed) when V^T H V is not positive definite.
  bool correctFrame();
  /// Puts the rows changed since the last call back into the sums: O(their links).
  void settleCoarse();
  /// V^T (b - H mu) and V^T H V as the store keeps them (the robot's terms and the rows
  /// not yet settled added), and the same from scratch over the whole map (O(N); tests).
  std::pair<Vec3, Mat3> coarseSums() const;
  std::pair<Vec3, Mat3> coarseSumsFromScratch() const;

  // ---- transactions: a step all or nothing
  /// Journals every change until commitTransaction() or rollbackTransaction(): the robot's
  /// state and links once, each landmark node's own blocks and link count before its first
  /// change, each link's value before each change (writeLink()), the means once if setMean()
  /// runs. O(what the step touches); no allocation once the journal has grown.
  void beginTransaction();
  void commitTransaction();
  /// Restores the store exactly as it was at beginTransaction(). marginalizeLandmark(),
  /// mergeLandmarks() and deleteLandmark() are not journaled (InvalidArgument inside one).
  void rollbackTransaction();

  // ---- anchors of the invariant linearisation (src/filters/invariant.hpp)
  /// The robot position H is anchored at.
  const Vec2& robotAnchor() const { return robot_anchor_; }
  /// The robot's motion moved its anchor with its mean (T(a + d) T(a)^-1 is the standard
  /// motion Jacobian whatever a).
  void moveRobotAnchor(const Vec2& d) { robot_anchor_ += d; }
  /// Re-anchors the robot at its mean: H <- M^-T H M^-1, b <- M^-T b + H' (I - M) mu with
  /// M = I + J (mu_p - a_p) e_theta^T (invariant.hpp): the change of variables
  /// delta' = M (x - mu), exact whether or not mu is H^-1 b. Touches the robot and its links. O(active).
  void reanchorRobot();
  /// The same for landmark `slot` (M = I + J (mu_l - a_l) e_theta^T over its rows): the
  /// robot's heading row gains the landmark's neighbours, which become active (linked to
  /// the robot) when they were not. O(links of the landmark).
  void reanchorLandmark(int slot) { reanchorLandmark(slot, mean(slot)); }
  /// Re-anchors landmark `slot` at `to` (a merge anchors two landmarks at one point).
  void reanchorLandmark(int slot, const Vec2& to);

  // ---- the local dense block
  /// Gathers H, b, mu of the robot and the landmarks `slots` (at most kMaxLocalLandmarks),
  /// in that order, into localH(), localB(), localMean(): [x (3), slots[0] (2), ...].
  void gather(std::span<const int> slots);
  /// gather() of the robot and the active landmarks, in robotLinks() order.
  void gatherActive();
  /// The gathered block put in the order `slots` (the same landmarks) without reading the
  /// store, with the passive terms of the last solveLocalMean(). Valid only while the store
  /// has changed since the gather through addObservationInBlock() and solveLocalMean() alone.
  void reorderGathered(std::span<const int> slots);
  /// Writes the gathered block back: H, b, mu, the robot links of active landmarks, and
  /// links among the landmarks (creating those that became non-zero: motion, paper fig. 4).
  void scatter();
  std::span<const int> gathered() const { return gathered_; }
  LocalMatrix& localH() { return local_H_; }
  LocalVector& localB() { return local_b_; }
  LocalVector& localMean() { return local_mu_; }

  // ---- Gauss-Seidel relaxation of the mean, eq. (42): mu_i = H_ii^-1 (b_i - sum H_ij mu_j)
  void relaxRobot();
  /// eq. (42) for one landmark, over-relaxed by `omega` (SeifOptions::omega; 1: eq. 42 itself):
  /// mu_i <- mu_i + omega (H_ii^-1 (b_i - sum_j H_ij mu_j) - mu_i).
  void relaxLandmark(int slot, double omega);
  /// Solves the gathered block's mean jointly, its links to the rest on the right-hand
  /// side. The block must hold exactly the active landmarks (in any order): the robot's
  /// links then all lie inside it, and the landmarks' links to passive ones outside.
  /// Passive::Reuse takes the block's links to the passive landmarks, sum_j H_ij mu_j, from
  /// the last solve on this block: valid while neither those links nor the passive means
  /// have changed (the iterated update, between its relinearisations).
  enum class Passive { Recompute, Reuse };
  void solveLocalMean(Passive passive = Passive::Recompute);
  /// Until the transaction ends: the landmarks whose rows of H the step may change between
  /// its solveLocalMean() calls; the block's other rows are factored once for all of them
  /// (FixedPartSolver: the same solution, rounded differently).
  void holdFixedPart(std::span<const int> changing) { fixed_part_.hold(changing); }
  /// addObservation() on the store and on the gathered block, which holds `slot`.
  void addObservationInBlock(int slot, const Eigen::Matrix<double, 5, 5>& H, const Eigen::Matrix<double, 5, 1>& b);
  /// gatherActive(); solveLocalMean().
  void relaxActive() {
    gatherActive();
    solveLocalMean();
  }
  /// Starts fetching landmark `slot`'s node into the cache (round 1 of relaxLandmarks()).
  void prefetch(int slot) const {  // its first 176 bytes: what relaxLandmark() reads (Node)
    const char* p = reinterpret_cast<const char*>(&nodes_[static_cast<std::size_t>(slot)]);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(p + 128);
    if (coarse_) __builtin_prefetch(p + 175);
  }
  /// relaxLandmark() of each of `slots` (prefetched), in order. Each relaxation chases three
  /// dependent pointers: node, links, neighbours' means. Their memory is prefetched first,
  /// round by round, so that the cache misses of the slots overlap instead of adding up.
  /// When the map fits in the caches (cacheResident()) the prefetches are skipped.
  void relaxLandmarks(std::span<const int> slots, double omega);

 private:
  friend struct CheckpointAccess;  // checkpoints: src/filters/*_state.cpp
  /// nodes_[slot] for a change: saved first when a transaction is open; its coarse terms
  /// taken out until settleCoarse() (touchCoarse()).
  Node& write(int slot);
  /// nodes_[slot] saved as write() does, its coarse terms left in: for a change of b alone,
  /// addToVector().
  Node& journal(int slot);
  /// b_slot += db, its coarse term V^T b kept current (O(1), no row recomputed).
  void addToVector(int slot, const Vec2& db);
  /// nodes_[slot].mu for a change (the relaxations' only write): its mean saved first.
  Vec2& writeMean(int slot);
  /// The value of link `index` of landmark `slot` for a change (write(slot) first): its value
  /// saved first when a transaction is open.
  LinkBlock& writeLink(int slot, std::size_t index);
  void requireNoTransaction(const char* what) const;
  /// H_{a,c} for a change (write(a)), or nullptr when they are not linked.
  LinkBlock* link(int a, int c);
  /// Links a and c, not linked yet, with H_{a,c} = H_ac (addToLink() without its search).
  void addLink(int a, int c, const Mat2& H_ac);
  void gatherListed();  // gather() of gathered_
  /// Marks each gathered landmark with its position (block_position_) for the life of the
  /// object, so that a node's links to the block are found in one pass over its links.
  class GatheredMarks;
  /// Links landmark `slot` to the robot (activates it) with a zero block; its position.
  int activate(int slot);
  /// The re-anchoring of reanchorRobot()/reanchorLandmark(): q = H dc over the variable's
  /// blanket (q_x on the robot, q_ in reanchor_q_ on landmarks), a = dc^T H dc and
  /// dc_r = dc^T (b - H mu), the residual on the re-anchored variable's position rows.
  void applyReanchor(const Vec3& q_x, double a, double dc_r);
  /// Sets landmark `slot`'s mean (journaled; its term of g follows).
  void assignMean(int slot, const Vec2& mean);
  /// V_i beta for a landmark whose rigid motions are taken at `ref`.
  Vec2 frameOffset(const Vec2& ref) const {
    const Vec2 r = ref - coarse_origin_;
    return frame_.head<2>() + frame_(2) * Vec2(-r.y(), r.x());
  }
  /// Node::mu that holds mean `m` at `ref`.
  Vec2 storedMean(const Vec2& m, const Vec2& ref) const { return coarse_ ? Vec2(m - frameOffset(ref)) : m; }
  /// Takes landmark `slot`'s terms out of g and A before its row of H, b or its H_ix changes
  /// (every write() does); settleCoarse() puts them back.
  void touchCoarse(int slot);
  /// Puts landmark `slot`'s terms, with its row w as it stands, back into the sums.
  void restoreCoarse(int slot);
  bool cacheResident() const;  // nodes and links fit in the caches: relaxLandmarks() skips prefetching
  void coarseTerms(int slot, const Mat23& w, Vec3& g, Mat3& A) const;  // landmark slot's terms with row w
  Mat23 landmarkBasis(const Vec2& ref) const;  // V_i, rigid motions taken at ref
  Mat23 coarseRow(int slot) const;  // (H V)_slot
  Mat3 robotBasis() const;          // V_x at the robot's mean
  void robotCoarseTerms(Vec3& g, Mat3& A) const;

  std::vector<int> ids_;
  Mat3 H_xx_;
  Vec3 b_x_;
  Vec3 mu_x_;
  Vec2 robot_anchor_;
  std::vector<RobotLink> robot_links_;
  std::vector<Node> nodes_;
  long step_ = 0;
  std::size_t blocks_touched_ = 0;
  std::size_t landmark_links_ = 0;      // landmark-landmark links (unordered pairs)
  std::size_t max_landmark_links_ = 0;  // most links any landmark has had

  // The gathered block, reused every step (no allocation in the steady state).
  std::vector<int> gathered_;
  LocalMatrix local_H_;
  LocalVector local_b_;
  LocalVector local_mu_;
  LocalVector local_rhs_;
  LocalVector local_passive_;     // sum over passive j of H_ij mu_j, per gathered row (solveLocalMean)
  // Per landmark slot, its position in the block while gather()/scatter() run, else -1
  // (GatheredMarks): 4 bytes a landmark, so the scans of links read a compact array.
  std::vector<int> block_position_;
  bool passive_current_ = false;  // local_passive_ holds the gathered block's, in its order
  FixedPartSolver fixed_part_;    // solveLocalMean() while a step holds a fixed part
  std::vector<std::pair<int, Vec2>> reanchor_q_;  // applyReanchor()'s landmark entries

  // The coarse level (above): the map's frame offset beta, the origin o of the rotations,
  // the robot's rows V_x the active landmarks' w hold, the landmark sums g and A, and the
  // landmarks whose terms are out of them until settleCoarse().
  bool coarse_ = false;
  Vec3 frame_ = Vec3::Zero();
  Vec2 coarse_origin_ = Vec2::Zero();
  Mat3 coarse_Vx_ = Mat3::Identity();
  Vec3 coarse_g_ = Vec3::Zero();
  Mat3 coarse_A_ = Mat3::Zero();
  std::vector<int> coarse_dirty_;

  struct Journal {
    bool open = false;
    long id = 0;  // of the open (or last) transaction
    Mat3 H_xx;
    Vec3 b_x, mu_x;
    Vec2 robot_anchor;
    Vec3 frame, coarse_g;
    Mat3 coarse_Vx, coarse_A;
    std::vector<RobotLink> robot_links;
    std::size_t nodes = 0, ids = 0, landmark_links = 0, max_landmark_links = 0;
    long step = 0;
    std::size_t blocks_touched = 0;
    // What was saved, in order: a whole node (saved[index]) or a mean (means_of[index]).
    struct Entry {
      int slot;
      bool whole;
      std::size_t index;
    };
    // A node without its link values: within a step a node's links only change in value
    // (each saved by writeLink() before its change) or grow at the end (links_count).
    struct SavedNode {
      Mat2 H, bound;
      Vec2 b, mu, anchor;
      Mat23 w;
      int active;
      std::size_t links_count;
    };
    struct SavedLink {
      int slot;
      std::size_t index;
      Mat2 H;
    };
    std::vector<Entry> entries;
    std::vector<SavedNode> saved;
    std::vector<SavedLink> saved_links;  // in the order saved
    std::vector<Vec2> means_of;
    bool means_saved = false;
    std::vector<Vec2> means;   // every landmark's mean, when setMean() ran
  };
  Journal journal_;
};

}  // namespace seif
