#pragma once
// One landmark's links in the SEIF's store (seif_store.hpp): the slot at the other end and
// the block H_{this, other} of each, in two arrays (a structure of arrays). The scans that
// look for a slot (the local block's gather and scatter, finding a link) read 4 bytes a link
// instead of 40; the relaxation streams 36 bytes a link instead of 40. Iterating yields
// {slot, H} pairs in the links' order, which every sum over them follows.
#include <seif/core/types.hpp>

#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

namespace seif {

class LinkList {
 public:
  // Unaligned: a block is 32 bytes, contiguous with the next.
  using Block = Eigen::Matrix<double, 2, 2, Eigen::DontAlign>;
  /// What iterating yields: a link's other end and its block (a view into the list).
  struct Ref {
    int slot;
    const Block& H;
  };
  class Iterator {
   public:
    Iterator(const LinkList& list, std::size_t i) : list_(&list), i_(i) {}
    Ref operator*() const { return {list_->slots_[i_], list_->blocks_[i_]}; }
    Iterator& operator++() {
      ++i_;
      return *this;
    }
    bool operator==(const Iterator& o) const { return i_ == o.i_; }
    bool operator!=(const Iterator& o) const { return i_ != o.i_; }

   private:
    const LinkList* list_;
    std::size_t i_;
  };

  std::size_t size() const { return slots_.size(); }
  Iterator begin() const { return {*this, 0}; }
  Iterator end() const { return {*this, slots_.size()}; }
  int slot(std::size_t i) const { return slots_[i]; }
  const Block& block(std::size_t i) const { return blocks_[i]; }
  Block& block(std::size_t i) { return blocks_[i]; }
  /// The other ends alone, in order (what a scan for a slot reads).
  std::span<const int> slots() const { return slots_; }
  std::span<const Block> blocks() const { return blocks_; }
  /// The position of the link to `slot`, or size() when there is none.
  std::size_t find(int slot) const {
    std::size_t i = 0;
    while (i < slots_.size() && slots_[i] != slot) ++i;
    return i;
  }
  /// The position of the link to `slot`, which must exist (the other end of a stored link).
  std::size_t at(int slot) const {
    const std::size_t i = find(slot);
    if (i == slots_.size()) throw std::logic_error("LinkList: a link without its reverse");
    return i;
  }

  void reserve(std::size_t n) {
    slots_.reserve(n);
    blocks_.reserve(n);
  }
  void push_back(int slot, const Block& H) {
    slots_.push_back(slot);
    blocks_.push_back(H);
  }
  /// Drops the links from position n on (n <= size()).
  void truncate(std::size_t n) {
    slots_.resize(n);
    blocks_.resize(n);
  }
  /// Removes link i, keeping the others' order.
  void erase(std::size_t i) {
    slots_.erase(slots_.begin() + static_cast<std::ptrdiff_t>(i));
    blocks_.erase(blocks_.begin() + static_cast<std::ptrdiff_t>(i));
  }
  /// Points link i at another slot (the store moves a landmark into a freed slot).
  void setSlot(std::size_t i, int slot) { slots_[i] = slot; }

 private:
  std::vector<int> slots_;
  std::vector<Block> blocks_;
};

}  // namespace seif
