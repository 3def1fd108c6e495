#include <seif/core/errors.hpp>
#include "core/small_llt.hpp"
#include "filters/seif_store.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <bitset>
#include <sstream>
#include <stdexcept>
#include <string>

namespace seif {

SeifStore::SeifStore(const Mat3& H_xx, const Vec3& mu_x)
    : H_xx_(H_xx), b_x_(H_xx * mu_x), mu_x_(mu_x), robot_anchor_(mu_x.head<2>()) {
  robot_links_.reserve(kMaxLocalLandmarks + 1);
  gathered_.reserve(kMaxLocalLandmarks + 1);
  journal_.robot_links.reserve(kMaxLocalLandmarks + 1);
  // What a step touches is bounded (the local block, the relaxed landmarks, their links):
  // room for it up front keeps the steady state free of allocation.
  journal_.entries.reserve(1024);
  journal_.saved.reserve(512);
  journal_.saved_links.reserve(8192);
  journal_.means_of.reserve(512);
}

// ---------------------------------------------------------------- transactions --------

void SeifStore::beginTransaction() {
  settleCoarse();
  fixed_part_.release();
  Journal& j = journal_;
  j.open = true;
  ++j.id;
  j.H_xx = H_xx_;
  j.b_x = b_x_;
  j.mu_x = mu_x_;
  j.robot_anchor = robot_anchor_;
  j.frame = frame_;
  j.coarse_g = coarse_g_;
  j.coarse_Vx = coarse_Vx_;
  j.coarse_A = coarse_A_;
  j.robot_links = robot_links_;  // at most kMaxLocalLandmarks: no allocation
  j.nodes = nodes_.size();
  j.ids = ids_.size();
  j.landmark_links = landmark_links_;
  j.max_landmark_links = max_landmark_links_;
  j.step = step_;
  j.blocks_touched = blocks_touched_;
  j.entries.clear();
  j.saved.clear();
  j.saved_links.clear();
  j.means_of.clear();
  j.means_saved = false;
}

void SeifStore::commitTransaction() {
  journal_.open = false;
  fixed_part_.release();
}

SeifStore::Node& SeifStore::write(int slot) {
  touchCoarse(slot);
  return journal(slot);
}

void SeifStore::addToVector(int slot, const Vec2& db) {
  Node& node = journal(slot);
  node.b += db;
  if (coarse_ && !node.coarse_dirty) coarse_g_.noalias() += landmarkBasis(node.ref).transpose() * db;
}

SeifStore::Node& SeifStore::journal(int slot) {
  Node& node = nodes_[static_cast<std::size_t>(slot)];
  Journal& j = journal_;
  if (j.open && node.journaled != j.id && static_cast<std::size_t>(slot) < j.nodes) {
    j.entries.push_back({slot, true, j.saved.size()});
    j.saved.push_back({node.H, node.bound, node.b, node.mu, node.anchor, node.w, node.active, node.links.size()});
    node.journaled = j.id;
  }
  return node;
}

Vec2& SeifStore::writeMean(int slot) {
  Node& node = nodes_[static_cast<std::size_t>(slot)];
  Journal& j = journal_;
  if (j.open && node.journaled != j.id && node.mean_journaled != j.id && static_cast<std::size_t>(slot) < j.nodes) {
    j.entries.push_back({slot, false, j.means_of.size()});
    j.means_of.push_back(node.mu);
    node.mean_journaled = j.id;
  }
  return node.mu;
}

void SeifStore::assignMean(int slot, const Vec2& mean) {
  Vec2& mu = writeMean(slot);
  if (coarse_) {
    const Node& n = node(slot);
    if (!n.coarse_dirty) coarse_g_.noalias() -= n.w.transpose() * (mean - (mu + frameOffset(n.ref)));  // -w_i^T dmu_i
    mu = mean - frameOffset(n.ref);
  } else {
    mu = mean;
  }
}

SeifStore::LinkBlock& SeifStore::writeLink(int slot, std::size_t index) {
  LinkBlock& H = nodes_[static_cast<std::size_t>(slot)].links.block(index);
  Journal& j = journal_;
  // Saved on every change (restored latest first, so the earliest value wins): cheaper than
  // marking each link, and a step changes each link a few times at most.
  if (j.open && static_cast<std::size_t>(slot) < j.nodes) j.saved_links.push_back({slot, index, H});
  return H;
}

void SeifStore::rollbackTransaction() {
  fixed_part_.release();
  Journal& j = journal_;
  if (!j.open) return;
  if (j.means_saved) {
    for (std::size_t s = 0; s < j.nodes; ++s) nodes_[s].mu = j.means[s];
  }
  // Latest first, so that each field ends at its earliest saved value; the link values
  // before the nodes, whose restore drops the links the step added.
  for (std::size_t k = j.saved_links.size(); k-- > 0;) {
    const Journal::SavedLink& l = j.saved_links[k];
    nodes_[static_cast<std::size_t>(l.slot)].links.block(l.index) = l.H;
  }
  for (std::size_t k = j.entries.size(); k-- > 0;) {
    const Journal::Entry& e = j.entries[k];
    Node& node = nodes_[static_cast<std::size_t>(e.slot)];
    if (e.whole) {
      const Journal::SavedNode& n = j.saved[e.index];
      node.H = n.H;
      node.bound = n.bound;
      node.b = n.b;
      node.mu = n.mu;
      node.anchor = n.anchor;
      node.w = n.w;
      node.active = n.active;
      node.links.truncate(n.links_count);  // links grow at the end within a step
    } else {
      node.mu = j.means_of[e.index];
    }
  }
  for (int slot : coarse_dirty_) {  // clean at beginTransaction(): their saved w is the sums'
    if (static_cast<std::size_t>(slot) < j.nodes) nodes_[static_cast<std::size_t>(slot)].coarse_dirty = false;
  }
  coarse_dirty_.clear();
  frame_ = j.frame;
  coarse_g_ = j.coarse_g;
  coarse_Vx_ = j.coarse_Vx;
  coarse_A_ = j.coarse_A;
  nodes_.resize(j.nodes);
  ids_.resize(j.ids);
  H_xx_ = j.H_xx;
  b_x_ = j.b_x;
  mu_x_ = j.mu_x;
  robot_anchor_ = j.robot_anchor;
  robot_links_ = j.robot_links;
  landmark_links_ = j.landmark_links;
  max_landmark_links_ = j.max_landmark_links;
  step_ = j.step;
  blocks_touched_ = j.blocks_touched;
  j.open = false;
}

void SeifStore::requireNoTransaction(const char* what) const {
  if (journal_.open) throw InvalidArgument(std::string("seif: ") + what + " inside a step (it is not journaled)");
}

// ---------------------------------------------------------------- links ---------------

SeifStore::LinkBlock* SeifStore::link(int a, int c) {
  const LinkList& links = write(a).links;
  const std::size_t i = links.find(c);
  return i < links.size() ? &writeLink(a, i) : nullptr;
}

const SeifStore::LinkBlock* SeifStore::findLink(int a, int c) const {
  const LinkList& links = node(a).links;
  const std::size_t i = links.find(c);
  return i < links.size() ? &links.block(i) : nullptr;
}

void SeifStore::addToLink(int a, int c, const Mat2& H_ac) {
  if (LinkBlock* h = link(a, c)) {
    *h += H_ac;
    *link(c, a) += H_ac.transpose();
    return;
  }
  addLink(a, c, H_ac);
}

void SeifStore::addLink(int a, int c, const Mat2& H_ac) {
  Node& na = write(a);
  Node& nc = write(c);
  na.links.push_back(c, H_ac);
  nc.links.push_back(a, H_ac.transpose());
  ++landmark_links_;
  max_landmark_links_ = std::max({max_landmark_links_, na.links.size() + (na.active >= 0 ? 1 : 0),
                                  nc.links.size() + (nc.active >= 0 ? 1 : 0)});
}

int SeifStore::addLandmark(int id, const Vec2& mu) {
  const int slot = size();
  ids_.push_back(id);
  nodes_.emplace_back();
  Node& n = nodes_.back();
  n.ref = mu;
  n.mu = storedMean(mu, mu);
  n.anchor = mu;
  if (coarse_) {  // its terms are zero until settleCoarse() adds them
    n.coarse_dirty = true;
    coarse_dirty_.push_back(slot);
  }
  return slot;
}

int SeifStore::activate(int slot) {
  if (node(slot).active >= 0) return node(slot).active;  // its robot link is robot_links_'s
  Node& node = write(slot);
  node.active = static_cast<int>(robot_links_.size());
  robot_links_.push_back({slot, Mat32::Zero(), step_});
  max_landmark_links_ = std::max(max_landmark_links_, node.links.size() + 1);
  return node.active;
}

namespace {
Vec2 quarterTurn(const Vec2& v) { return Vec2(-v.y(), v.x()); }

/// sum over `links` of H_ij m(j), in four interleaved partial sums: with one running sum
/// each link's additions wait for the previous link's (a relaxation's ~130 links are then
/// bound by the adder's latency, not its throughput).
template <typename MeanOf>
Vec2 linkSum(const LinkList& links, const MeanOf& m) {
  Vec2 s0 = Vec2::Zero(), s1 = Vec2::Zero(), s2 = Vec2::Zero(), s3 = Vec2::Zero();
  const std::size_t n = links.size();
  const int* slot = links.slots().data();
  const LinkList::Block* H = links.blocks().data();
  std::size_t e = 0;
  for (; e + 4 <= n; e += 4) {
    s0.noalias() += H[e] * m(slot[e]);
    s1.noalias() += H[e + 1] * m(slot[e + 1]);
    s2.noalias() += H[e + 2] * m(slot[e + 2]);
    s3.noalias() += H[e + 3] * m(slot[e + 3]);
  }
  for (; e < n; ++e) s0.noalias() += H[e] * m(slot[e]);
  return (s0 + s1) + (s2 + s3);
}
}  // namespace

void SeifStore::reanchorRobot() {
  // invariant.hpp: dc = J (mu_p - a_p) on the robot's position rows; q = H dc.
  const Vec2 dc = quarterTurn(mu_x_.head<2>() - robot_anchor_);
  robot_anchor_ = mu_x_.head<2>();
  if (dc.isZero(0.0)) return;
  const Vec3 q_x = H_xx_.leftCols<2>() * dc;
  Vec3 r_x = b_x_ - H_xx_ * mu_x_;  // the residual b - H mu on the robot's rows
  reanchor_q_.clear();
  for (const RobotLink& l : robot_links_) {
    reanchor_q_.emplace_back(l.slot, l.H.topRows<2>().transpose() * dc);
    r_x.noalias() -= l.H * mean(l.slot);
  }
  applyReanchor(q_x, dc.dot(q_x.head<2>()), dc.dot(r_x.head<2>()));
}

void SeifStore::reanchorLandmark(int slot, const Vec2& to) {
  Node& node = journal(slot);  // its H and links stay: only the heading's row and b change
  const Vec2 dc = quarterTurn(to - node.anchor);
  node.anchor = to;
  if (dc.isZero(0.0)) return;
  const Vec3 q_x = node.active >= 0 ? Vec3(robot_links_[static_cast<std::size_t>(node.active)].H * dc) : Vec3::Zero();
  Vec2 r = node.b - node.H * mean(slot);  // the residual b - H mu on the landmark's rows
  if (node.active >= 0) r.noalias() -= robot_links_[static_cast<std::size_t>(node.active)].H.transpose() * mu_x_;
  reanchor_q_.clear();
  reanchor_q_.emplace_back(slot, node.H * dc);
  for (const Link& k : node.links) {
    reanchor_q_.emplace_back(k.slot, k.H.transpose() * dc);  // H_{k,l} dc
    r.noalias() -= k.H * mean(k.slot);
  }
  applyReanchor(q_x, dc.dot(reanchor_q_.front().second), dc.dot(r));
}

void SeifStore::applyReanchor(const Vec3& q_x, double a, double dc_r) {
  // invariant.hpp: H' = M^-T H M^-1 = H - q e_t^T - e_t q^T + a e_t e_t^T, and b as the same
  // change of variables about mu (delta' = M delta, delta = x - mu):
  //   b' = M^-T b + H' (I - M) mu = b + (H' - H) mu + (M^-T - I)(b - H mu)
  //      = b - mu_t q - e_t (q^T mu - a mu_t + dc^T r),  r = b - H mu.
  // When mu is the mean H and b hold (r = 0) the mean stays; when the amortised mean lags,
  // the posterior moves only by dc (m_t - mu_t), not along the heading's covariance column by
  // Sigma e_t dc^T r (the lag's residual fed into b). Only the heading row and column change.
  const double mu_t = mu_x_(2);
  double q_mu = q_x.dot(mu_x_);
  for (const auto& [slot, q] : reanchor_q_) q_mu += q.dot(mean(slot));
  H_xx_.col(2) -= q_x;
  H_xx_.row(2) -= q_x.transpose();
  H_xx_(2, 2) += a;
  b_x_ -= mu_t * q_x;
  b_x_(2) -= q_mu - a * mu_t + dc_r;
  for (const auto& [slot, q] : reanchor_q_) {
    RobotLink& l = robot_links_[static_cast<std::size_t>(activate(slot))];
    l.H.row(2) -= q.transpose();
    addToVector(slot, -mu_t * q);
  }
  blocks_touched_ += 1 + reanchor_q_.size();
}

void SeifStore::addObservation(int slot, const Eigen::Matrix<double, 5, 5>& H,
                               const Eigen::Matrix<double, 5, 1>& b) {
  Node& node = write(slot);
  H_xx_ += H.topLeftCorner<3, 3>();
  b_x_ += b.head<3>();
  node.H += H.bottomRightCorner<2, 2>();
  node.b += b.tail<2>();
  RobotLink& l = robot_links_[static_cast<std::size_t>(activate(slot))];  // observing activates
  l.H += H.topRightCorner<3, 2>();
  l.last_seen = step_;
  blocks_touched_ += 3;
}

void SeifStore::removeRobotLink(int slot) {
  Node& node = write(slot);
  const std::size_t pos = static_cast<std::size_t>(node.active);
  node.active = -1;
  if (pos + 1 != robot_links_.size()) {
    robot_links_[pos] = robot_links_.back();
    write(robot_links_[pos].slot).active = static_cast<int>(pos);
  }
  robot_links_.pop_back();
}

void SeifStore::marginalizeLandmark(int slot) {
  requireNoTransaction("marginalizeLandmark()");
  touchCoarse(slot);
  for (const Link& k : node(slot).links) touchCoarse(k.slot);
  const Node& l = nodes_[static_cast<std::size_t>(slot)];
  Eigen::LLT<Mat2> llt(l.H);
  if (llt.info() != Eigen::Success) {
    throw NumericError("seif: information of landmark " + std::to_string(ids_[static_cast<std::size_t>(slot)]) +
                       " is not positive definite; it cannot be marginalised out");
  }
  // The blanket's blocks H_{a,l} (a = -1 the robot), then the Schur complement pair by pair.
  std::vector<std::pair<int, Eigen::Matrix<double, Eigen::Dynamic, 2, 0, 3, 2>>> blanket;
  if (l.active >= 0) blanket.emplace_back(-1, robot_links_[static_cast<std::size_t>(l.active)].H);
  for (const Link& k : l.links) blanket.emplace_back(k.slot, k.H.transpose());  // H_{a,l} = H_{l,a}^T
  const Vec2 W_b = llt.solve(l.b);  // H_ll^-1 b_l
  for (std::size_t i = 0; i < blanket.size(); ++i) {
    const auto& [a, H_al] = blanket[i];
    const Eigen::Matrix<double, 2, Eigen::Dynamic, 0, 2, 3> W_a = llt.solve(H_al.transpose());  // H_ll^-1 H_la
    for (std::size_t j = i; j < blanket.size(); ++j) {
      const auto& [c, H_cl] = blanket[j];
      Eigen::MatrixXd D = (H_cl * W_a).transpose();  // H_al H_ll^-1 H_lc
      if (a == c) D = (0.5 * (D + D.transpose())).eval();  // diagonal blocks stay symmetric
      if (a < 0 && c < 0) {
        H_xx_ -= D;
      } else if (a < 0) {  // the robot and landmark c
        Node& nc = nodes_[static_cast<std::size_t>(c)];
        if (nc.active < 0) {
          nc.active = static_cast<int>(robot_links_.size());
          robot_links_.push_back({c, Mat32::Zero(), step_});
        }
        robot_links_[static_cast<std::size_t>(nc.active)].H -= D;
      } else if (a == c) {
        nodes_[static_cast<std::size_t>(a)].H -= D;
      } else {
        addToLink(a, c, -D);
      }
    }
    if (a < 0) {
      b_x_ -= H_al * W_b;
    } else {
      nodes_[static_cast<std::size_t>(a)].b -= H_al * W_b;
    }
  }
  deleteLandmark(slot);
}

void SeifStore::mergeLandmarks(int keep, int drop) {
  requireNoTransaction("mergeLandmarks()");
  touchCoarse(keep);
  touchCoarse(drop);
  Node& k = nodes_[static_cast<std::size_t>(keep)];
  const Node d = nodes_[static_cast<std::size_t>(drop)];  // a copy: links change below
  // H'_kk = H_kk + H_kd + H_dk + H_dd, b'_k = b_k + b_d.
  k.H += d.H;
  if (const LinkBlock* H_kd = findLink(keep, drop)) {
    const Mat2 kd = *H_kd;
    nodes_[static_cast<std::size_t>(keep)].H += kd + kd.transpose();
  }
  nodes_[static_cast<std::size_t>(keep)].b += d.b;
  for (const Link& l : d.links) {
    if (l.slot != keep) addToLink(keep, l.slot, l.H);
  }
  if (d.active >= 0) {
    const RobotLink& r = robot_links_[static_cast<std::size_t>(d.active)];
    Node& nk = nodes_[static_cast<std::size_t>(keep)];
    if (nk.active < 0) {
      nk.active = static_cast<int>(robot_links_.size());
      robot_links_.push_back({keep, Mat32::Zero(), r.last_seen});
    }
    RobotLink& rk = robot_links_[static_cast<std::size_t>(nk.active)];
    rk.H += robot_links_[static_cast<std::size_t>(nodes_[static_cast<std::size_t>(drop)].active)].H;
    rk.last_seen = std::max(rk.last_seen, robot_links_[static_cast<std::size_t>(nodes_[static_cast<std::size_t>(drop)].active)].last_seen);
  }
  deleteLandmark(drop);
}

void SeifStore::deleteLandmark(int slot) {
  requireNoTransaction("deleteLandmark()");
  touchCoarse(slot);
  // Unlink it from its neighbours and the robot.
  for (const Link& l : nodes_[static_cast<std::size_t>(slot)].links) {
    touchCoarse(l.slot);
    LinkList& back = nodes_[static_cast<std::size_t>(l.slot)].links;
    back.erase(back.at(slot));
    --landmark_links_;
  }
  if (nodes_[static_cast<std::size_t>(slot)].active >= 0) removeRobotLink(slot);
  // Its terms are out of the coarse sums; its neighbours' go back before slots move.
  nodes_[static_cast<std::size_t>(slot)].coarse_dirty = false;
  settleCoarse();
  // The last slot moves into its place.
  const int last = size() - 1;
  if (slot != last) {
    nodes_[static_cast<std::size_t>(slot)] = std::move(nodes_.back());
    ids_[static_cast<std::size_t>(slot)] = ids_.back();
    Node& moved = nodes_[static_cast<std::size_t>(slot)];
    for (const Link& l : moved.links) {
      LinkList& back = nodes_[static_cast<std::size_t>(l.slot)].links;
      back.setSlot(back.at(last), slot);
    }
    if (moved.active >= 0) robot_links_[static_cast<std::size_t>(moved.active)].slot = slot;
  }
  nodes_.pop_back();
  ids_.pop_back();
}

void SeifStore::detachRobot(const Vec3& mu_x) {
  for (const RobotLink& l : robot_links_) write(l.slot).active = -1;
  robot_links_.clear();
  H_xx_.setZero();
  b_x_.setZero();
  mu_x_ = mu_x;
  robot_anchor_ = mu_x.head<2>();
}

void SeifStore::setMean(const Eigen::VectorXd& mu) {
  if (journal_.open && !journal_.means_saved) {  // O(N), as the exact mean that calls it
    journal_.means.resize(journal_.nodes);
    for (std::size_t s = 0; s < journal_.nodes; ++s) journal_.means[s] = nodes_[s].mu;
    journal_.means_saved = true;
  }
  mu_x_ = mu.head<3>();
  frame_.setZero();
  for (int s = 0; s < size(); ++s) nodes_[static_cast<std::size_t>(s)].mu = mu.segment<2>(StateLayout::landmark(s));
  if (coarse_) enableCoarse();  // the sums again, O(N) as this
}

// ---------------------------------------------------------------- the local block ------

class SeifStore::GatheredMarks {
 public:
  explicit GatheredMarks(SeifStore& store) : store_(store) {
    store.block_position_.resize(store.nodes_.size(), -1);  // -1 outside a gather: resized freely
    for (std::size_t i = 0; i < store.gathered_.size(); ++i) {
      int& mark = store.block_position_[static_cast<std::size_t>(store.gathered_[i])];
      if (mark >= 0) {
        clear(i);
        throw InvalidArgument("seif: a landmark listed twice in a local block");
      }
      mark = static_cast<int>(i);
    }
  }
  ~GatheredMarks() { clear(store_.gathered_.size()); }
  GatheredMarks(const GatheredMarks&) = delete;
  GatheredMarks& operator=(const GatheredMarks&) = delete;

 private:
  void clear(std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) store_.block_position_[static_cast<std::size_t>(store_.gathered_[i])] = -1;
  }
  SeifStore& store_;
};

namespace {
/// A link of a gathered landmark to another gathered one: its index in the landmark's links
/// and the other's position in the block.
struct BlockLink {
  int index;
  int position;
};
using BlockLinks = std::array<BlockLink, kMaxLocalLandmarks + 1>;  // one spare: written, not kept

/// The links of `node` whose other end is gathered (`positions`: each landmark's position in
/// the block, or -1) at a position after `after`, in their order; returns how many. Without a
/// branch per link: each is written and kept only when it counts (a landmark has ~10^2 links,
/// a handful in the block, and a branch on each mispredicted about as often as it is taken
/// cost more than the loop's loads).
int linksInBlock(const std::vector<int>& positions, const SeifStore::Node& node, int after, BlockLinks& out) {
  int count = 0;
  const std::span<const int> slots = node.links.slots();
  const int n = static_cast<int>(slots.size());
  for (int e = 0; e < n; ++e) {
    const int j = positions[static_cast<std::size_t>(slots[static_cast<std::size_t>(e)])];
    out[static_cast<std::size_t>(count)] = {e, j};
    count += j > after ? 1 : 0;
    // At most one link per other gathered landmark; never taken, so never mispredicted.
    if (count >= kMaxLocalLandmarks) throw std::logic_error("SeifStore: a landmark linked twice to one other");
  }
  return count;
}
}  // namespace

void SeifStore::gather(std::span<const int> slots) {
  gathered_.assign(slots.begin(), slots.end());
  gatherListed();
}

void SeifStore::gatherActive() {
  gathered_.clear();
  for (const RobotLink& l : robot_links_) gathered_.push_back(l.slot);
  gatherListed();
}

void SeifStore::reorderGathered(std::span<const int> slots) {
  const auto k = static_cast<Eigen::Index>(gathered_.size());
  if (static_cast<Eigen::Index>(slots.size()) != k) throw std::logic_error("SeifStore::reorderGathered: other landmarks");
  // rows[i]: where slots[i] sits in the gathered block now
  std::array<Eigen::Index, kMaxLocalDim> rows{};
  for (Eigen::Index r = 0; r < 3; ++r) rows[static_cast<std::size_t>(r)] = r;
  for (Eigen::Index i = 0; i < k; ++i) {
    const auto at = std::find(gathered_.begin(), gathered_.end(), slots[static_cast<std::size_t>(i)]);
    if (at == gathered_.end()) throw std::logic_error("SeifStore::reorderGathered: other landmarks");
    const auto from = 3 + 2 * static_cast<Eigen::Index>(at - gathered_.begin());
    rows[static_cast<std::size_t>(3 + 2 * i)] = from;
    rows[static_cast<std::size_t>(4 + 2 * i)] = from + 1;
  }
  const Eigen::Index n = 3 + 2 * k;
  const auto from = [&rows](Eigen::Index r) { return rows[static_cast<std::size_t>(r)]; };
  const auto permute = [&](LocalVector& v) {  // local_rhs_ as the scratch copy
    local_rhs_ = v;
    for (Eigen::Index r = 0; r < n; ++r) v(r) = local_rhs_(from(r));
  };
  permute(local_b_);
  permute(local_mu_);
  if (passive_current_) permute(local_passive_);
  const LocalMatrix H = local_H_;
  for (Eigen::Index c = 0; c < n; ++c) {
    for (Eigen::Index r = 0; r < n; ++r) local_H_(r, c) = H(from(r), from(c));
  }
  gathered_.assign(slots.begin(), slots.end());
}

void SeifStore::addObservationInBlock(int slot, const Eigen::Matrix<double, 5, 5>& H,
                                      const Eigen::Matrix<double, 5, 1>& b) {
  const auto at = std::find(gathered_.begin(), gathered_.end(), slot);
  if (at == gathered_.end()) throw std::logic_error("SeifStore::addObservationInBlock: a landmark outside the block");
  addObservation(slot, H, b);
  // The same sums on the block's copies (gatherListed() copied them from the store).
  const auto r = 3 + 2 * static_cast<Eigen::Index>(at - gathered_.begin());
  local_H_.topLeftCorner<3, 3>() += H.topLeftCorner<3, 3>();
  local_b_.head<3>() += b.head<3>();
  local_H_.block<2, 2>(r, r) += H.bottomRightCorner<2, 2>();
  local_b_.segment<2>(r) += b.tail<2>();
  local_H_.block<3, 2>(0, r) += H.topRightCorner<3, 2>();
  local_H_.block<2, 3>(r, 0) = local_H_.block<3, 2>(0, r).transpose();
}

void SeifStore::gatherListed() {
  passive_current_ = false;
  const int k = static_cast<int>(gathered_.size());
  if (k > kMaxLocalLandmarks) {
    throw InvalidArgument("seif: a local block holds at most " + std::to_string(kMaxLocalLandmarks) +
                                " landmarks");
  }
  const GatheredMarks marks(*this);
  BlockLinks block_links;
  const int n = 3 + 2 * k;
  local_H_.setZero(n, n);
  local_b_.resize(n);
  local_mu_.resize(n);
  local_H_.topLeftCorner<3, 3>() = H_xx_;
  local_b_.head<3>() = b_x_;
  local_mu_.head<3>() = mu_x_;
  for (int i = 0; i < k; ++i) {
    const int a = gathered_[static_cast<std::size_t>(i)];
    const Node& n_a = node(a);
    const int r = 3 + 2 * i;
    local_H_.block<2, 2>(r, r) = n_a.H;
    local_b_.segment<2>(r) = n_a.b;
    local_mu_.segment<2>(r) = mean(a);
    if (n_a.active >= 0) {
      const Mat32& H_xl = robot_links_[static_cast<std::size_t>(n_a.active)].H;
      local_H_.block<3, 2>(0, r) = H_xl;
      local_H_.block<2, 3>(r, 0) = H_xl.transpose();
    }
    // H_{a,c} from a's side for each later c in the block
    const int in_block = linksInBlock(block_position_, n_a, i, block_links);
    for (int e = 0; e < in_block; ++e) {
      const BlockLink& bl = block_links[static_cast<std::size_t>(e)];
      const LinkBlock& H_ac = n_a.links.block(static_cast<std::size_t>(bl.index));
      const int c = 3 + 2 * bl.position;
      local_H_.block<2, 2>(r, c) = H_ac;
      local_H_.block<2, 2>(c, r) = H_ac.transpose();
    }
  }
  blocks_touched_ += static_cast<std::size_t>((k + 1) * (k + 1));
}

void SeifStore::scatter() {
  const int k = static_cast<int>(gathered_.size());
  H_xx_ = local_H_.topLeftCorner<3, 3>();
  b_x_ = local_b_.head<3>();
  mu_x_ = local_mu_.head<3>();
  // The coarse level: a row that is exact before the scatter (its terms in the sums) changes
  // only by the blocks written here, dw_i = dH_ii V_i + sum_j dH_ij V_j over the gathered j;
  // it is updated by that and put back in the sums at the end, not recomputed from its links.
  std::array<bool, kMaxLocalLandmarks> row_kept{};
  std::array<Mat23, kMaxLocalLandmarks> basis;
  std::array<Mat23, kMaxLocalLandmarks> row_change;
  if (coarse_) {
    for (int i = 0; i < k; ++i) {
      const Node& n = node(gathered_[static_cast<std::size_t>(i)]);
      const auto a = static_cast<std::size_t>(i);
      row_kept[a] = !n.coarse_dirty;
      basis[a] = landmarkBasis(n.ref);
      row_change[a].setZero();
    }
  }
  // Each pair's block is written from the upper triangle (i < j), H_{c,a} as its transpose.
  std::array<std::bitset<kMaxLocalLandmarks>, kMaxLocalLandmarks> linked{};
  {
    const GatheredMarks marks(*this);
    BlockLinks block_links;
    for (int i = 0; i < k; ++i) {
      const auto a = static_cast<std::size_t>(i);
      Node& node = write(gathered_[a]);
      const int r = 3 + 2 * i;
      if (row_kept[a]) row_change[a].noalias() += (local_H_.block<2, 2>(r, r) - node.H) * basis[a];
      node.H = local_H_.block<2, 2>(r, r);
      node.b = local_b_.segment<2>(r);
      node.mu = storedMean(local_mu_.segment<2>(r), node.ref);
      if (node.active >= 0) robot_links_[static_cast<std::size_t>(node.active)].H = local_H_.block<3, 2>(0, r);
      const int in_block = linksInBlock(block_position_, node, -1, block_links);
      for (int m = 0; m < in_block; ++m) {
        const auto e = static_cast<std::size_t>(block_links[static_cast<std::size_t>(m)].index);
        const int j = block_links[static_cast<std::size_t>(m)].position;
        linked[static_cast<std::size_t>(std::min(i, j))].set(static_cast<std::size_t>(std::max(i, j)));
        const Mat2 H_ij =
            i < j ? Mat2(local_H_.block<2, 2>(r, 3 + 2 * j)) : Mat2(local_H_.block<2, 2>(3 + 2 * j, r).transpose());
        LinkBlock& stored = writeLink(gathered_[a], e);
        if (row_kept[a]) row_change[a].noalias() += (H_ij - stored) * basis[static_cast<std::size_t>(j)];
        stored = H_ij;
      }
    }
  }
  for (int i = 0; i < k; ++i) {  // motion creates links among the active landmarks (paper fig. 4)
    for (int j = i + 1; j < k; ++j) {
      const auto a = static_cast<std::size_t>(i), c = static_cast<std::size_t>(j);
      if (linked[a].test(c)) continue;
      const Mat2 block = local_H_.block<2, 2>(3 + 2 * i, 3 + 2 * j);
      if (block.cwiseAbs().maxCoeff() > 0.0) {
        addLink(gathered_[a], gathered_[c], block);  // not linked (above): no search
        if (row_kept[a]) row_change[a].noalias() += block * basis[c];
        if (row_kept[c]) row_change[c].noalias() += block.transpose() * basis[a];
      }
    }
  }
  if (coarse_) {
    for (int i = 0; i < k; ++i) {
      const auto a = static_cast<std::size_t>(i);
      if (!row_kept[a]) continue;
      nodes_[static_cast<std::size_t>(gathered_[a])].w += row_change[a];
      restoreCoarse(gathered_[a]);
    }
    // Settled here: out of the list (a later write lists them again).
    std::erase_if(coarse_dirty_, [this](int slot) { return !nodes_[static_cast<std::size_t>(slot)].coarse_dirty; });
  }
  blocks_touched_ += static_cast<std::size_t>((k + 1) * (k + 1));
}

// ---------------------------------------------------------------- relaxation ----------

void SeifStore::relaxRobot() {
  // eq. (42): mu_x = H_xx^-1 (b_x - sum_l H_xl mu_l)
  Vec3 rhs = b_x_;
  for (const RobotLink& l : robot_links_) rhs.noalias() -= l.H * mean(l.slot);
  Eigen::LLT<Mat3> llt(H_xx_);
  if (llt.info() != Eigen::Success) {
    throw NumericError("seif: robot information block is not positive definite after " +
                       std::to_string(step_) + " motion updates");
  }
  mu_x_ = llt.solve(rhs);
  blocks_touched_ += 1 + robot_links_.size();
}

void SeifStore::relaxLandmark(int slot, double omega) {
  const Node& node = nodes_[static_cast<std::size_t>(slot)];
  Vec2 rhs = node.b;
  if (coarse_ && !node.coarse_dirty) {
    // sum_j H_ij (mu_j + V_j beta) = sum_j H_ij mu_j + (w_i - H_ii V_i) beta with the kept
    // row w_i = H_ii V_i + sum_j H_ij V_j (seif_store_coarse.cpp): the links read mu alone.
    rhs.noalias() -= (node.w - node.H * landmarkBasis(node.ref)) * frame_;
    rhs -= linkSum(node.links, [this](int j) -> const Vec2& { return nodes_[static_cast<std::size_t>(j)].mu; });
  } else {
    rhs -= linkSum(node.links, [this](int j) { return mean(j); });
  }
  if (node.active >= 0) {
    rhs.noalias() -= robot_links_[static_cast<std::size_t>(node.active)].H.transpose() * mu_x_;
  }
  Eigen::LLT<Mat2> llt(node.H);
  if (llt.info() != Eigen::Success) {
    std::ostringstream msg;
    msg << "seif: information of landmark " << ids_[static_cast<std::size_t>(slot)]
        << " is not positive definite after " << step_ << " motion updates";
    throw NumericError(msg.str());
  }
  if (omega == 1.0) {
    assignMean(slot, llt.solve(rhs));
  } else {  // successive over-relaxation (Saad, Iterative Methods for Sparse Linear Systems, §4.1)
    const Vec2 current = mean(slot);
    assignMean(slot, Vec2(current + omega * (llt.solve(rhs) - current)));
  }
  blocks_touched_ += 1 + node.links.size() + (node.active >= 0 ? 1 : 0);
}

bool SeifStore::cacheResident() const {
  // The nodes and their links within a few MiB: Victoria Park's map (400 landmarks, 130 links
  // each, 2.3 MB) relaxes 10 % faster without the prefetches; the bench's 10^5 and 10^6 need them.
  constexpr std::size_t kResidentBytes = std::size_t{4} << 20;
  return nodes_.size() * sizeof(Node) + 2 * landmark_links_ * (sizeof(int) + sizeof(LinkBlock)) <= kResidentBytes;
}

void SeifStore::relaxLandmarks(std::span<const int> slots, double omega) {
  if (cacheResident()) {  // the prefetches would only add work
    for (int s : slots) relaxLandmark(s, omega);
    return;
  }
  for (int s : slots) {  // round 2: their links (round 1, the nodes: prefetch())
    const LinkList& links = node(s).links;
    const auto prefetch = [](const void* from, const void* to) {
      for (const char* p = static_cast<const char*>(from); p < static_cast<const char*>(to); p += 64) __builtin_prefetch(p);
    };
    prefetch(links.slots().data(), links.slots().data() + links.size());
    prefetch(links.blocks().data(), links.blocks().data() + links.size());
  }
  for (int s : slots) {  // round 3: their neighbours' means
    for (int j : node(s).links.slots()) __builtin_prefetch(&node(j).mu);
  }
  for (int s : slots) relaxLandmark(s, omega);
}

void SeifStore::solveLocalMean(Passive passive) {
  // Block Gauss-Seidel on the gathered variables L jointly (eq. 42 with S_i the projection
  // onto L): mu_L = H_LL^-1 (b_L - H_{L,rest} mu_rest). With every active landmark in L the
  // robot is linked only inside L; each landmark's links to passive ones go to the right.
  if (passive == Passive::Reuse && !passive_current_) {
    throw std::logic_error("SeifStore::solveLocalMean: no passive terms of this block to reuse");
  }
  if (passive == Passive::Recompute || !passive_current_) {
    local_passive_.setZero(local_b_.size());
    for (std::size_t i = 0; i < gathered_.size(); ++i) {
      const Node& n = node(gathered_[i]);
      local_passive_.segment<2>(3 + 2 * static_cast<Eigen::Index>(i)) =
          linkSum(n.links, [this](int j) { return node(j).active < 0 ? mean(j) : Vec2(Vec2::Zero()); });
      blocks_touched_ += n.links.size();
    }
    passive_current_ = true;
  }
  local_rhs_ = local_b_ - local_passive_;
  bool ok = true;
  if (fixed_part_.held()) {  // holdFixedPart(): the rows the step does not change factored once
    ok = fixed_part_.solve(local_H_, local_rhs_, gathered_, local_mu_);
  } else {
    const SmallLLT<LocalMatrix> llt(local_H_);
    ok = llt.info() == Eigen::Success;
    if (ok) local_mu_ = llt.solve(local_rhs_);
  }
  if (!ok) {
    throw NumericError("seif: the information of the robot and its active landmarks is not "
                       "positive definite after " + std::to_string(step_) + " motion updates");
  }
  mu_x_ = local_mu_.head<3>();
  for (std::size_t i = 0; i < gathered_.size(); ++i) {
    assignMean(gathered_[i], local_mu_.segment<2>(3 + 2 * static_cast<Eigen::Index>(i)));
  }
}

// ---------------------------------------------------------------- reading out ---------

Eigen::SparseMatrix<double> SeifStore::sparseInformation() const {
  const int n = 3 + 2 * size();
  std::vector<Eigen::Triplet<double>> t;
  auto addBlock = [&t](int r, int c, const auto& B) {
    for (int i = 0; i < B.rows(); ++i)
      for (int j = 0; j < B.cols(); ++j) t.emplace_back(r + i, c + j, B(i, j));
  };
  addBlock(0, 0, H_xx_);
  for (const RobotLink& l : robot_links_) {
    const int c = StateLayout::landmark(l.slot);
    addBlock(0, c, l.H);
    addBlock(c, 0, Mat23(l.H.transpose()));
  }
  for (int s = 0; s < size(); ++s) {
    const Node& n_s = node(s);
    const int r = StateLayout::landmark(s);
    addBlock(r, r, n_s.H);
    for (const Link& l : n_s.links) addBlock(r, StateLayout::landmark(l.slot), l.H);
  }
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(t.begin(), t.end());
  return H;
}

Eigen::SparseMatrix<double> SeifStore::lowerInformation() const {
  // The lower triangle of H in compressed columns, written in place from the block store
  // (no triplets): the one copy of H a factorisation needs, at a third of the peak memory.
  const int n = 3 + 2 * size();
  std::vector<int> count(static_cast<std::size_t>(n), 0);  // entries per column
  count[0] = 3 + 2 * static_cast<int>(robot_links_.size());
  count[1] = 2 + 2 * static_cast<int>(robot_links_.size());
  count[2] = 1 + 2 * static_cast<int>(robot_links_.size());
  for (int s = 0; s < static_cast<int>(nodes_.size()); ++s) {
    int below = 0;
    for (const Link& l : nodes_[static_cast<std::size_t>(s)].links) below += l.slot > s ? 2 : 0;
    count[static_cast<std::size_t>(StateLayout::landmark(s))] = 2 + below;
    count[static_cast<std::size_t>(StateLayout::landmark(s)) + 1] = 1 + below;
  }
  Eigen::SparseMatrix<double> H(n, n);
  H.reserve(Eigen::Map<const Eigen::VectorXi>(count.data(), n));
  std::vector<std::pair<int, const LinkBlock*>> below;  // a landmark's links to later slots, sorted
  for (int c = 0; c < 3; ++c) {
    for (int r = c; r < 3; ++r) H.insert(r, c) = H_xx_(r, c);
  }
  // Robot columns: rows of the active landmarks in any order (insert() keeps them sorted).
  for (const RobotLink& l : robot_links_) {
    const int r = StateLayout::landmark(l.slot);
    for (int c = 0; c < 3; ++c) {
      H.insert(r, c) = l.H(c, 0);
      H.insert(r + 1, c) = l.H(c, 1);
    }
  }
  for (int s = 0; s < static_cast<int>(nodes_.size()); ++s) {
    const Node& node = nodes_[static_cast<std::size_t>(s)];
    const int c = StateLayout::landmark(s);
    below.clear();
    for (const Link& l : node.links) {
      if (l.slot > s) below.emplace_back(l.slot, &l.H);
    }
    std::sort(below.begin(), below.end());
    for (int k = 0; k < 2; ++k) {
      for (int r = k; r < 2; ++r) H.insert(c + r, c + k) = node.H(r, k);
      for (const auto& [slot, block] : below) {
        const int r = StateLayout::landmark(slot);
        H.insert(r, c + k) = (*block)(k, 0);  // H_{other, this} = H_{this, other}^T
        H.insert(r + 1, c + k) = (*block)(k, 1);
      }
    }
  }
  H.makeCompressed();
  return H;
}

Eigen::VectorXd SeifStore::informationVector() const {
  Eigen::VectorXd b(3 + 2 * size());
  b.head<3>() = b_x_;
  for (int s = 0; s < size(); ++s) b.segment<2>(StateLayout::landmark(s)) = node(s).b;
  return b;
}

Eigen::VectorXd SeifStore::mean() const {
  Eigen::VectorXd mu(3 + 2 * size());
  mu.head<3>() = mu_x_;
  for (int s = 0; s < size(); ++s) mu.segment<2>(StateLayout::landmark(s)) = mean(s);
  return mu;
}

FilterStats SeifStore::stats() const {
  FilterStats s;
  s.landmarks = nodes_.size();
  s.robot_links = robot_links_.size();
  s.links = s.robot_links + landmark_links_;
  s.max_landmark_links = max_landmark_links_;
  s.blocks_touched = blocks_touched_;
  return s;
}

}  // namespace seif
