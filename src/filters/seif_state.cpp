// SeifSlam's and SeifStore's state in a checkpoint (checkpoint_access.hpp): every node in
// slot order with its links in their own vector order, the robot links in theirs, the
// counters and the random engine's exact state.
#include "checkpoint_access.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace seif {

namespace {

// Bytes of the smallest stored link (slot, H) and robot link (slot, H, last_seen).
constexpr std::size_t kLinkBytes = 9 + 9 + 4 * 8;
constexpr std::size_t kRobotLinkBytes = 9 + 9 + 6 * 8 + 9;

std::string engineState(const std::mt19937_64& rng) {
  std::ostringstream os;
  os << rng;
  return os.str();
}

}  // namespace

void CheckpointAccess::write(ArchiveWriter& out, const SeifStore& s) {
  out.section("seif-store");
  writeIndex(out, s.ids_);
  out.fixed(s.H_xx_);
  out.fixed(s.b_x_);
  out.fixed(s.mu_x_);
  out.fixed(s.robot_anchor_);
  out.count(s.nodes_.size());
  for (const SeifStore::Node& n : s.nodes_) {
    out.fixed(n.H);
    out.fixed(n.b);
    out.fixed(n.mu);
    out.fixed(n.anchor);
    out.fixed(n.bound);
    out.i64(n.active);
    out.count(n.links.size());
    for (const SeifStore::Link& l : n.links) {
      out.i64(l.slot);
      out.fixed(l.H);
    }
  }
  out.count(s.robot_links_.size());
  for (const SeifStore::RobotLink& l : s.robot_links_) {
    out.i64(l.slot);
    out.fixed(l.H);
    out.i64(l.last_seen);
  }
  out.i64(s.step_);
  out.u64(s.blocks_touched_);
  out.u64(s.landmark_links_);
  out.u64(s.max_landmark_links_);
  // The mean's coarse level: the sums as kept (recomputing them would round differently).
  out.u64(s.coarse_ ? 1 : 0);
  if (!s.coarse_) return;
  out.fixed(s.frame_);
  out.fixed(s.coarse_origin_);
  out.fixed(s.coarse_Vx_);
  out.fixed(s.coarse_g_);
  out.fixed(s.coarse_A_);
  for (const SeifStore::Node& n : s.nodes_) {
    out.fixed(n.ref);
    out.fixed(n.w);
  }
  // Rows waiting for the next settle, in order (none between steps, removals and merges,
  // which settle their own; kept so that a checkpoint never depends on it).
  out.count(s.coarse_dirty_.size());
  for (int slot : s.coarse_dirty_) out.i64(slot);
}

void CheckpointAccess::read(ArchiveReader& in, SeifStore& s) {
  in.section("seif-store");
  std::unordered_map<int, int> slots;
  readIndex(in, s.ids_, slots);
  const int size = static_cast<int>(s.ids_.size());
  in.fixed("robot information", s.H_xx_, true);
  in.fixed("robot information vector", s.b_x_, true);
  in.fixed("robot mean", s.mu_x_, true);
  if (in.version() >= 2) {
    in.fixed("robot anchor", s.robot_anchor_, true);
  } else {
    s.robot_anchor_ = s.mu_x_.head<2>();
  }
  // Information is positive on its diagonal (deactivation ranks links by it, sqrt'd).
  if (!(s.H_xx_.diagonal().minCoeff() > 0.0)) in.fail("robot information is not positive on its diagonal");
  const std::size_t nodes = in.count("node count", (in.version() >= 4 ? 5 : in.version() >= 2 ? 4 : 3) * 9 + 9 + 9);
  if (nodes != static_cast<std::size_t>(size)) {
    in.fail(std::to_string(nodes) + " nodes for " + std::to_string(size) + " landmarks");
  }
  s.nodes_.clear();
  s.nodes_.resize(nodes);
  std::size_t link_ends = 0;
  for (std::size_t a = 0; a < nodes; ++a) {
    SeifStore::Node& n = s.nodes_[a];
    in.fixed("landmark information", n.H, true);
    if (!(n.H.diagonal().minCoeff() > 0.0)) in.fail("landmark information is not positive on its diagonal");
    in.fixed("landmark information vector", n.b, true);
    in.fixed("landmark mean", n.mu, true);
    if (in.version() >= 2) {
      in.fixed("landmark anchor", n.anchor, true);
    } else {
      n.anchor = n.mu;
    }
    if (in.version() >= 4) {  // older files: no bounds (SeifOptions::bounds off)
      in.fixed("landmark covariance bound", n.bound, true);
      if (!(n.bound.diagonal().minCoeff() >= 0.0)) in.fail("a landmark's covariance bound is negative on its diagonal");
    }
    n.active = static_cast<int>(in.i64In("active position", -1, kMaxLocalLandmarks - 1));
    const std::size_t links = in.count("link count", kLinkBytes);
    n.links.reserve(links);
    for (std::size_t k = 0; k < links; ++k) {
      const int slot = static_cast<int>(in.i64In("linked slot", 0, size - 1));
      if (static_cast<std::size_t>(slot) == a) in.fail("a landmark linked to itself");
      if (n.links.find(slot) < n.links.size()) in.fail("a link stored twice");
      SeifStore::LinkBlock H;
      in.fixed("link information", H, true);
      n.links.push_back(slot, H);
    }
    link_ends += links;
  }
  for (std::size_t a = 0; a < nodes; ++a) {
    for (const SeifStore::Link& l : s.nodes_[a].links) {
      if (!s.findLink(l.slot, static_cast<int>(a))) in.fail("a landmark link without its reverse");
    }
  }
  const std::size_t robot_links = in.count("robot link count", kRobotLinkBytes);
  if (robot_links > static_cast<std::size_t>(kMaxLocalLandmarks)) {
    in.fail(std::to_string(robot_links) + " active landmarks, more than a local block holds");
  }
  s.robot_links_.clear();
  for (std::size_t k = 0; k < robot_links; ++k) {
    SeifStore::RobotLink l;
    l.slot = static_cast<int>(in.i64In("active slot", 0, size - 1));
    if (s.nodes_[static_cast<std::size_t>(l.slot)].active != static_cast<int>(k)) {
      in.fail("robot link " + std::to_string(k) + " disagrees with its landmark's active position");
    }
    in.fixed("robot link information", l.H, true);
    l.last_seen = static_cast<long>(in.i64("last seen"));
    s.robot_links_.push_back(l);
  }
  const auto active = static_cast<std::size_t>(
      std::count_if(s.nodes_.begin(), s.nodes_.end(), [](const SeifStore::Node& n) { return n.active >= 0; }));
  if (active != robot_links) in.fail("active landmarks without a robot link");
  // Steps count up from 0; a robot link was last seen at one of them (the stale rule takes
  // step - last_seen).
  s.step_ = static_cast<long>(in.i64In("step", 0, std::numeric_limits<std::int64_t>::max() / 2));
  for (const SeifStore::RobotLink& l : s.robot_links_) {
    if (l.last_seen < 0 || l.last_seen > s.step_) {
      in.fail("an active landmark last seen at step " + std::to_string(l.last_seen) + ", outside 0.." +
              std::to_string(s.step_));
    }
  }
  s.blocks_touched_ = static_cast<std::size_t>(in.u64("blocks touched"));
  s.landmark_links_ = static_cast<std::size_t>(in.u64("landmark links"));
  if (2 * s.landmark_links_ != link_ends) in.fail("the landmark link count disagrees with the links stored");
  s.max_landmark_links_ = static_cast<std::size_t>(in.u64("most links of a landmark"));
  s.coarse_ = in.version() >= 8 && in.u64Max("coarse level", 1) == 1;
  s.coarse_dirty_.clear();
  if (!s.coarse_) {
    s.frame_.setZero();
    return;
  }
  in.fixed("coarse frame", s.frame_, true);
  in.fixed("coarse origin", s.coarse_origin_, true);
  in.fixed("coarse robot basis", s.coarse_Vx_, true);
  in.fixed("coarse residual", s.coarse_g_, true);
  in.fixed("coarse information", s.coarse_A_, true);
  for (SeifStore::Node& n : s.nodes_) {
    in.fixed("landmark coarse reference", n.ref, true);
    in.fixed("landmark coarse row", n.w, true);
    n.coarse_dirty = false;
  }
  const std::size_t dirty = in.count("coarse rows to settle", 9);
  for (std::size_t k = 0; k < dirty; ++k) {
    const int slot = static_cast<int>(in.i64In("coarse row to settle", 0, size - 1));
    SeifStore::Node& n = s.nodes_[static_cast<std::size_t>(slot)];
    if (n.coarse_dirty) in.fail("a coarse row listed twice");
    n.coarse_dirty = true;
    s.coarse_dirty_.push_back(slot);
  }
  if (in.version() == 8) {
    // Version 8 kept an active landmark's row with its robot term H_jx V_x (and its share of
    // the sums); they are now added fresh each step (SeifStore::robotCoarseTerms()).
    for (const SeifStore::RobotLink& l : s.robot_links_) {
      SeifStore::Node& n = s.nodes_[static_cast<std::size_t>(l.slot)];
      const Mat23 HV = l.H.transpose() * s.coarse_Vx_;
      n.w -= HV;
      if (n.coarse_dirty) continue;  // its terms are out of the sums until the next settle
      s.coarse_A_.noalias() -= s.landmarkBasis(n.ref).transpose() * HV;
      s.coarse_g_.noalias() += HV.transpose() * s.mean(l.slot);
    }
  }
}

void CheckpointAccess::write(ArchiveWriter& out, const SeifSlam& f) {
  out.section("seif");
  // The book's index is the store's (written with it).
  writeGate(out, f.book_.gate_);
  write(out, f.store_);
  writeFirstEstimates(out, f.book_.fej_);
  out.str(engineState(f.rng_));
  out.u64(f.relax_cursor_);
  out.f64(f.last_sparsification_residual_);
  out.u64(f.eseif_relocalizations_);
  out.u64(f.eseif_deferrals_);
  out.u64(f.eseif_fallbacks_);
  out.u64(f.pending_motion_ ? 1 : 0);  // SeifOptions::Motion::Deferred: the increment held
  if (f.pending_motion_) {
    out.fixed(f.pending_motion_->delta);
    out.fixed(f.pending_motion_->J_delta_x);
    out.fixed(f.pending_motion_->U);
    out.u64(f.pending_controls_);
  }
  out.u64(f.controls_since_observation_);  // Motion::Deferred: whether the next empty update solves the block
  out.f64(f.information_scale_);  // Sparsify::Conservative's kappa
  out.u64(f.scalings_);
  // Whether the next update skips that block's solve (a Gathered block is in buffers a
  // checkpoint does not hold: it loads as Stale, and is read again to the same values).
  out.u64(f.block_ == SeifSlam::ActiveBlock::Solved ? 1 : 0);
  // RelaxOrder::Wildfire's queue (ids, in order) and per slot where each last spread from;
  // empty with the other orders.
  const RelaxFrontier::State fire = f.frontier_.state();
  out.count(fire.queue.size());
  for (int id : fire.queue) out.i64(id);
  out.count(fire.spread_from.size());
  for (std::size_t s = 0; s < fire.spread_from.size(); ++s) {
    out.fixed(fire.spread_from[s]);
    out.u64(fire.is_queued[s]);
  }
}

void CheckpointAccess::read(ArchiveReader& in, SeifSlam& f) {
  in.section("seif");
  readGate(in, f.book_.gate_);
  read(in, f.store_);
  if (f.store_.coarse() != (f.options_.coarse == SeifOptions::Coarse::Rigid &&
                            f.options_.mean == SeifOptions::Mean::Amortized)) {
    in.fail("the store's coarse level disagrees with the filter's options");
  }
  f.book_.ids_ = f.store_.ids();
  f.book_.slot_.clear();
  for (int s = 0; s < f.book_.size(); ++s) f.book_.slot_.emplace(f.book_.ids_[static_cast<std::size_t>(s)], s);
  readFirstEstimates(in, f.book_.fej_, LandmarkBook::keepsFirstEstimates(f.book_.linearization()), f.store_.size());
  const std::string rng = in.str("random engine state");
  std::istringstream is(rng);
  is >> f.rng_;
  // Only the canonical text (what operator<< writes) is accepted: save-load-save is byte-identical.
  if (is.fail() || engineState(f.rng_) != rng) in.fail("invalid random engine state");
  f.relax_cursor_ = static_cast<std::size_t>(in.u64("relaxation cursor"));
  f.last_sparsification_residual_ = in.f64("last sparsification residual");
  f.eseif_relocalizations_ = static_cast<std::size_t>(in.u64("eseif relocalizations"));
  f.eseif_deferrals_ = static_cast<std::size_t>(in.u64("eseif deferrals"));
  f.eseif_fallbacks_ = static_cast<std::size_t>(in.u64("eseif fallbacks"));
  f.pending_motion_.reset();
  f.pending_controls_ = 0;
  if (in.version() >= 5 && in.u64Max("deferred motion", 1) == 1) {
    MotionIncrement m;
    in.fixed("deferred motion increment", m.delta, true);
    in.fixed("deferred motion Jacobian", m.J_delta_x, true);
    in.fixed("deferred motion noise", m.U, true);
    f.pending_controls_ = static_cast<std::size_t>(in.u64("deferred controls"));
    if (f.pending_controls_ == 0) in.fail("a deferred motion of no controls");
    f.pending_motion_ = m;
  }
  // Earlier files: the controls still held (what the rule counted before version 14).
  f.controls_since_observation_ =
      in.version() >= 14 ? static_cast<std::size_t>(in.u64("controls since the last observation")) : f.pending_controls_;
  if (f.controls_since_observation_ < f.pending_controls_) in.fail("fewer controls since the last observation than held");
  f.information_scale_ = 1.0;
  f.scalings_ = 0;
  if (in.version() >= 6) {
    f.information_scale_ = in.f64("information scale");
    if (!(f.information_scale_ >= 1.0) || !std::isfinite(f.information_scale_)) in.fail("information scale must be finite and >= 1");
    f.scalings_ = static_cast<std::size_t>(in.u64("information scalings"));
  }
  // Earlier files: solved again (the same mean up to rounding).
  f.block_ = in.version() >= 10 && in.u64Max("solved robot-active block", 1) == 1 ? SeifSlam::ActiveBlock::Solved
                                                                                   : SeifSlam::ActiveBlock::Stale;
  RelaxFrontier::State fire;
  if (in.version() >= 13) {
    fire.queue.resize(in.count("wildfire queue", 8));
    for (int& id : fire.queue) id = static_cast<int>(in.i64In("wildfire queue id", std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
    const std::size_t slots = in.count("wildfire slots", 24);
    fire.spread_from.resize(slots);
    fire.is_queued.resize(slots);
    for (std::size_t s = 0; s < slots; ++s) {
      in.fixed("wildfire spread point", fire.spread_from[s], true);
      fire.is_queued[s] = static_cast<unsigned char>(in.u64Max("wildfire queued flag", 1));
    }
  }
  const std::size_t expected = f.wildfire() ? static_cast<std::size_t>(f.store_.size()) : 0;
  if (fire.spread_from.size() != expected || (!f.wildfire() && !fire.queue.empty())) {
    in.fail("the wildfire relaxation's state disagrees with the filter's options and map");
  }
  f.frontier_.restore(std::move(fire));
  f.invalidateFactor();
}

}  // namespace seif
