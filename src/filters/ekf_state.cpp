// EkfSlam's state in a checkpoint (checkpoint_access.hpp).
#include "checkpoint_access.hpp"

namespace seif {

void CheckpointAccess::write(ArchiveWriter& out, const EkfSlam& f) {
  out.section("ekf");
  writeBook(out, f.book_);
  out.vector(f.mu_);
  out.matrix(f.sigma_);
}

void CheckpointAccess::read(ArchiveReader& in, EkfSlam& f) {
  in.section("ekf");
  readBook(in, f.book_);
  const Eigen::Index n = StateLayout::size(f.book_.size());
  f.mu_ = in.vector("ekf mean", true);
  if (f.mu_.size() != n) in.fail("ekf mean has " + std::to_string(f.mu_.size()) + " entries, expected " + std::to_string(n));
  f.sigma_ = in.matrix("ekf covariance", true);
  if (f.sigma_.rows() != n || f.sigma_.cols() != n) in.fail("ekf covariance does not match the map's size");
}

}  // namespace seif
