// The wildfire order of the amortised mean's relaxation (seif_relax_frontier.hpp).
#include "filters/seif_relax_frontier.hpp"

#include "filters/seif_store.hpp"

namespace seif {

namespace {
// Grows v's capacity to at least n, geometrically (a map grows one landmark at a time).
template <class V>
void reserveAtLeast(V& v, std::size_t n) {
  if (v.capacity() < n) v.reserve(std::max(n, 2 * v.capacity()));
}
}  // namespace

void RelaxFrontier::addLandmark(const Vec2& mu) {
  spread_from_.push_back(mu);
  is_queued_.push_back(0);
  // No allocation in a step that adds no landmark: between steps the queue holds at most
  // twice its live entries (begin()), and a step queues each landmark at most once; a step's
  // journal saves a slot per pop, per spread and per newly queued neighbour.
  const std::size_t n = spread_from_.size();
  reserveAtLeast(queue_, 3 * n + 16);
  reserveAtLeast(changes_, n + 4 * (std::min(relax_, n) + active_) + 16);
}

void RelaxFrontier::removeSlot(int slot) {
  // The queue holds ids, which do not move; next() skips the one no longer in the map.
  const auto s = static_cast<std::size_t>(slot);
  spread_from_[s] = spread_from_.back();
  is_queued_[s] = is_queued_.back();
  spread_from_.pop_back();
  is_queued_.pop_back();
}

void RelaxFrontier::save(int slot) {
  const auto s = static_cast<std::size_t>(slot);
  if (open_ && s < begin_slots_) changes_.push_back({slot, spread_from_[s], is_queued_[s]});
}

void RelaxFrontier::moved(const SeifStore& store, int slot) {
  const auto s = static_cast<std::size_t>(slot);
  const SeifStore::Node& node = store.node(slot);
  // Node::mu, not mean(): the coarse level's rigid correction of the whole map moves no
  // landmark against its neighbours.
  const Vec2 d = node.mu - spread_from_[s];
  if (d.dot(node.H * d) > threshold_ * threshold_) spread(store, slot);
}

void RelaxFrontier::spread(const SeifStore& store, int slot) {
  const SeifStore::Node& node = store.node(slot);
  save(slot);
  spread_from_[static_cast<std::size_t>(slot)] = node.mu;
  for (const SeifStore::Link& l : node.links) {
    const auto n = static_cast<std::size_t>(l.slot);
    if (is_queued_[n]) continue;
    save(l.slot);
    is_queued_[n] = 1;
    queue_.push_back(store.ids()[n]);
  }
}

void RelaxFrontier::begin() {
  // The consumed front goes between steps (amortised O(1) a pop; no allocation once the
  // queue has reached its largest).
  if (head_ > queue_.size() / 2) {
    queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
  begin_head_ = head_;
  begin_size_ = queue_.size();
  begin_slots_ = spread_from_.size();
  changes_.clear();
  open_ = true;
}

void RelaxFrontier::rollback() {
  if (!open_) return;
  open_ = false;
  // Pops only move head_ and pushes only append: the entries of the queue at begin() are intact.
  head_ = begin_head_;
  queue_.resize(begin_size_);
  spread_from_.resize(begin_slots_);
  is_queued_.resize(begin_slots_);
  for (std::size_t k = changes_.size(); k-- > 0;) {  // latest first: the earliest value wins
    const Change& c = changes_[k];
    spread_from_[static_cast<std::size_t>(c.slot)] = c.spread_from;
    is_queued_[static_cast<std::size_t>(c.slot)] = c.is_queued;
  }
  changes_.clear();
}

RelaxFrontier::State RelaxFrontier::state() const {
  return {std::vector<int>(queue_.begin() + static_cast<std::ptrdiff_t>(head_), queue_.end()), spread_from_, is_queued_};
}

void RelaxFrontier::restore(State s) {
  queue_ = std::move(s.queue);
  head_ = 0;
  spread_from_ = std::move(s.spread_from);
  is_queued_ = std::move(s.is_queued);
  changes_.clear();
  open_ = false;
  begin_slots_ = spread_from_.size();
  begin_head_ = 0;
  begin_size_ = queue_.size();
}

}  // namespace seif
