// Nearest neighbour with individual compatibility (Probabilistic Robotics §7.5, §12.7):
// every pairing inside the accept gate, taken greedily by Mahalanobis distance, one
// landmark per observation and one observation per landmark in a scan.
#include "association/scan.hpp"

#include <algorithm>
#include <unordered_set>

namespace seif {

std::vector<int> assignNearestNeighbour(const ScanProblem& scan) {
  std::vector<Pairing> all;
  for (const auto& list : scan.compatible) all.insert(all.end(), list.begin(), list.end());
  std::sort(all.begin(), all.end(), [](const Pairing& a, const Pairing& b) {
    return a.d2 != b.d2 ? a.d2 < b.d2 : (a.observation != b.observation ? a.observation < b.observation : a.landmark < b.landmark);
  });
  std::vector<int> out(scan.compatible.size(), -1);
  std::unordered_set<int> taken;
  for (const Pairing& p : all) {
    if (out[static_cast<std::size_t>(p.observation)] >= 0 || taken.count(p.landmark)) continue;
    out[static_cast<std::size_t>(p.observation)] = p.landmark;
    taken.insert(p.landmark);
  }
  return out;
}

}  // namespace seif
