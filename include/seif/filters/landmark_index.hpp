#pragma once
// Landmark id <-> slot in the state vector, in order of first sight.
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace seif {

class LandmarkIndex {
 public:
  /// Slot of `id`, or -1 when the landmark is not in the map.
  int find(int id) const {
    const auto it = slot_.find(id);
    return it == slot_.end() ? -1 : it->second;
  }
  /// Slot of `id`; throws std::out_of_range naming `filter` when it is not in the map.
  int require(int id, const char* filter) const {
    const int s = find(id);
    if (s < 0) {
      throw std::out_of_range(std::string(filter) + ": landmark " + std::to_string(id) +
                              " is not in the map");
    }
    return s;
  }
  /// Adds `id` (which must be new) and returns its slot.
  int add(int id) {
    const int s = static_cast<int>(ids_.size());
    slot_.emplace(id, s);
    ids_.push_back(id);
    return s;
  }
  const std::vector<int>& ids() const { return ids_; }
  int size() const { return static_cast<int>(ids_.size()); }
  /// First index of landmark slot s in the state vector [x, y, th, l0x, l0y, ...].
  static int stateIndex(int s) { return 3 + 2 * s; }

 private:
  std::vector<int> ids_;
  std::unordered_map<int, int> slot_;
};

}  // namespace seif
