// EifSlam's state in a checkpoint (checkpoint_access.hpp).
#include "checkpoint_access.hpp"

namespace seif {

void CheckpointAccess::write(ArchiveWriter& out, const EifSlam& f) {
  out.section("eif");
  writeBook(out, f.book_);
  out.matrix(f.H_);
  out.vector(f.b_);
  out.vector(f.mu_);
}

void CheckpointAccess::read(ArchiveReader& in, EifSlam& f) {
  in.section("eif");
  readBook(in, f.book_);
  const Eigen::Index n = StateLayout::size(f.book_.size());
  f.H_ = in.matrix("eif information matrix", true);
  if (f.H_.rows() != n || f.H_.cols() != n) in.fail("eif information matrix does not match the map's size");
  f.b_ = in.vector("eif information vector", true);
  if (f.b_.size() != n) in.fail("eif information vector does not match the map's size");
  f.mu_ = in.vector("eif mean", true);
  if (f.mu_.size() != n) in.fail("eif mean does not match the map's size");
  f.llt_valid_ = false;
}

}  // namespace seif
