// The SEIF's mean recovery (algorithm.md §2): amortised block Gauss-Seidel, paper eq. (42),
// or the exact sparse solve of H mu = b. SeifOptions::mean chooses; SeifSlam::update calls.
#include "core/sparse_marginals.hpp"
#include <seif/core/errors.hpp>
#include "filters/seif_slam.hpp"

#include <algorithm>
#include <array>
#include <string>

namespace seif {

void SeifSlam::recoverMean(bool with_active, ActiveBlock block) {
  // §2: one block Gauss-Seidel pass over the active landmarks, the robot and K others.
  // In a map much larger than the caches, relaxing a random landmark costs three dependent
  // cache misses (SeifStore::relaxLandmarks). The K landmarks are therefore drawn first (the
  // same draws in the same order: the result is unchanged) and prefetched in chunks, so
  // that their misses overlap instead of adding up: at 10^6 landmarks this phase then takes
  // ~20 % less (it is still the one part of a step whose time grows with the map, through
  // cache and TLB misses).
  constexpr int kChunk = 16;
  std::array<int, kChunk> picks{};
  const int n = store_.size();
  std::uniform_int_distribution<int> pick(0, std::max(0, n - 1));
  // K is capped at the map's size: relaxing a landmark twice in one pass is pointless.
  const int random = std::min(options_.relax, n);
  // Wildfire: the active landmarks' means moved with the last measurements (the block
  // solves); each that moved far enough queues its neighbours first.
  const bool wildfire = this->wildfire();
  if (wildfire) {
    for (const SeifStore::RobotLink& l : store_.robotLinks()) frontier_.moved(store_, l.slot);
  }
  auto draw = [&](int count) {
    for (int i = 0; i < count; ++i) {
      int slot = wildfire ? frontier_.next([this](int id) { return book_.find(id); }) : -1;
      if (slot < 0) {
        slot = options_.relax_order == SeifOptions::RelaxOrder::Random
                   ? pick(rng_)
                   : static_cast<int>(relax_cursor_++ % static_cast<std::size_t>(n));
      }
      picks[static_cast<std::size_t>(i)] = slot;
      store_.prefetch(slot);
    }
  };
  int chunk = std::min(random, kChunk);
  draw(chunk);
  if (block == ActiveBlock::Solved) {
    // deactivateSurplus() solved the block last, and nothing has changed since.
  } else if (with_active && block == ActiveBlock::Gathered) {
    store_.solveLocalMean();  // applyMotion() left the block gathered: the same values
  } else if (with_active) {
    store_.relaxActive();
  } else {
    store_.relaxRobot();
  }
  for (int done = 0; done < random;) {
    store_.relaxLandmarks(std::span<const int>(picks.data(), static_cast<std::size_t>(chunk)), options_.omega);
    if (wildfire) {
      for (int i = 0; i < chunk; ++i) frontier_.moved(store_, picks[static_cast<std::size_t>(i)]);
    }
    done += chunk;
    chunk = std::min(random - done, kChunk);
    draw(chunk);
  }
  // SeifOptions::coarse: then the map's rigid motion (seif_store_coarse.cpp). Skipped, the
  // fine relaxation alone, when V^T H V is not positive definite.
  if (store_.coarse()) store_.correctFrame();
}

void SeifSlam::relaxMean(int sweeps) {
  if (sweeps < 0) throw InvalidArgument("seif: relaxMean: sweeps must be >= 0, found " + std::to_string(sweeps));
  settleMotion();
  block_ = ActiveBlock::Stale;
  for (int s = 0; s < sweeps; ++s) {
    store_.relaxRobot();
    for (int i = 0; i < store_.size(); ++i) store_.relaxLandmark(i, options_.omega);
  }
}

Eigen::VectorXd SeifSlam::exactMean() const { return factor().solve(store().informationVector()); }

std::optional<Eigen::VectorXd> SeifSlam::posteriorMean() const {
  if (options_.mean == SeifOptions::Mean::Exact) return std::nullopt;
  return exactMean();
}

void SeifSlam::recoverExactMean() {
  block_ = ActiveBlock::Stale;
  store_.setMean(exactMean());
}
}  // namespace seif
