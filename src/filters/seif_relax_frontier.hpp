#pragma once
// The amortised mean's wildfire order (SeifOptions::RelaxOrder::Wildfire): which landmarks
// the K relaxations of a step visit. Gauss-Seidel's step on landmark i (eq. 42) changes only
// where a neighbour's mean has moved since i was last relaxed; so each landmark whose mean
// moves by more than `threshold` of its conditional standard deviation,
//   (mu_i - r_i)^T H_ii (mu_i - r_i) > threshold^2   (r_i: its mean when it last spread),
// queues its neighbours (first in, first out; each once), and the relaxation takes the queue
// before the cyclic order. The change spreads from where the measurements moved the mean,
// through the links, as iSAM2's "wildfire" spreads a back-substitution (Kaess et al., IJRR
// 2012, §5.2), instead of visiting the settled parts of the map as often as the rest.
// O(links) per landmark that spreads; a step's changes are undone by rollback().
#include <seif/core/types.hpp>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace seif {

class SeifStore;

class RelaxFrontier {
 public:
  /// What a landmark's mean must move, in its conditional standard deviations, to spread;
  /// `relax` (K) and `active` size the journal: a step relaxes at most min(K, map size)
  /// landmarks besides the active ones, in at most two passes.
  RelaxFrontier(double threshold, int relax, int active)
      : threshold_(threshold), relax_(static_cast<std::size_t>(std::max(relax, 0))),
        active_(static_cast<std::size_t>(std::max(active, 0))) {}

  /// A new landmark, slot size(), its neighbours' queue entry not yet spread from mu.
  void addLandmark(const Vec2& mu);
  /// Slot `slot` deleted and the last slot moved into it (SeifStore::deleteLandmark).
  void removeSlot(int slot);
  /// After landmark `slot`'s mean changed: spreads when it moved past the threshold.
  void moved(const SeifStore& store, int slot);
  /// Queues the neighbours of `slot` whatever its move (after a merge, which gives it new
  /// neighbours and a new mean), and it spreads from its mean now.
  void spread(const SeifStore& store, int slot);
  /// The next queued landmark that is still in the map (slot_of(id) >= 0), or -1 when none is.
  template <class SlotOf>
  int next(const SlotOf& slot_of) {
    while (head_ < queue_.size()) {
      const int slot = slot_of(queue_[head_++]);
      if (slot < 0) continue;  // removed or merged away since it was queued
      save(slot);
      is_queued_[static_cast<std::size_t>(slot)] = 0;
      return slot;
    }
    return -1;
  }
  std::size_t queued() const { return queue_.size() - head_; }

  /// A step: journals the changes until commit(); rollback() restores the state at begin().
  void begin();
  void commit() { open_ = false; }
  void rollback();

  // Checkpoints (seif_state.cpp): the queue's landmark ids in order; per slot the mean it
  // last spread from and whether it is queued.
  struct State {
    std::vector<int> queue;
    std::vector<Vec2> spread_from;
    std::vector<unsigned char> is_queued;
  };
  State state() const;
  void restore(State s);

 private:
  struct Change {
    int slot;
    Vec2 spread_from;
    unsigned char is_queued;
  };
  void save(int slot);

  double threshold_;
  std::size_t relax_, active_;
  std::vector<int> queue_;  // landmark ids; [head_, end) are queued
  std::size_t head_ = 0;
  std::vector<Vec2> spread_from_;
  std::vector<unsigned char> is_queued_;
  // The journal of the open step.
  bool open_ = false;
  std::size_t begin_head_ = 0, begin_size_ = 0, begin_slots_ = 0;
  std::vector<Change> changes_;
};

}  // namespace seif
