// The associator (include/seif/association/association.hpp): candidates from a grid of landmark
// means, the two gates, a strategy per file (nn.cpp, jcbb.cpp),
// provisional landmarks, and the scoring against Observation::truth.
#include <seif/core/errors.hpp>
#include <seif/association/association.hpp>
#include "association/candidate_grid.hpp"
#include "association/footprint.hpp"
#include "association/scan.hpp"
#include "association/track_score.hpp"
#include "core/binary_archive.hpp"
#include "filters/option_values.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace seif {

AssociationMethod parseAssociationMethod(std::string_view s) {
  if (s == "known") return AssociationMethod::Known;
  if (s == "nn") return AssociationMethod::NearestNeighbour;
  if (s == "jcbb") return AssociationMethod::Jcbb;
  throw InvalidArgument("unknown association '" + std::string(s) + "' (expected known, nn or jcbb)");
}

std::string_view associationMethodName(AssociationMethod m) {
  switch (m) {
    case AssociationMethod::Known: return "known";
    case AssociationMethod::NearestNeighbour: return "nn";
    case AssociationMethod::Jcbb: return "jcbb";
  }
  return "known";
}

ProvisionalPlace parseProvisionalPlace(std::string_view s) {
  if (s == "filter") return ProvisionalPlace::Filter;
  if (s == "held") return ProvisionalPlace::Held;
  throw InvalidArgument("unknown provisional place '" + std::string(s) + "' (expected filter or held)");
}

std::string_view provisionalPlaceName(ProvisionalPlace p) { return p == ProvisionalPlace::Held ? "held" : "filter"; }

ConfirmRule parseConfirmRule(std::string_view s) {
  if (s == "count") return ConfirmRule::Count;
  if (s == "score") return ConfirmRule::Score;
  throw InvalidArgument("unknown confirm rule '" + std::string(s) + "' (expected count or score)");
}

std::string_view confirmRuleName(ConfirmRule r) { return r == ConfirmRule::Score ? "score" : "count"; }

std::string_view gateMarginalName(std::optional<MarginalMode> m) { return m ? marginalModeName(*m) : "auto"; }

std::optional<MarginalMode> parseGateMarginal(std::string_view s) {
  if (s == "auto") return std::nullopt;
  try {
    return parseMarginalMode(s);
  } catch (const InvalidArgument&) {
    throw InvalidArgument("unknown gate marginal '" + std::string(s) + "' (expected auto, exact, local or conservative)");
  }
}

bool needsCovarianceBounds(const AssociationOptions& o) {
  return o.method != AssociationMethod::Known && o.marginal == MarginalMode::Conservative;
}

namespace {

/// Delta = y_a - y_b with Sigma_Delta = F_Delta Sigma F_Delta^T, F_Delta = [I, -I]:
/// Sigma_aa + Sigma_bb - Sigma_ab - Sigma_ba, from a marginal holding both at rows ra, rb.
double correspondenceD2(const Marginal& m, Eigen::Index ra, Eigen::Index rb) {
  const Vec2 delta = m.mean.segment<2>(ra) - m.mean.segment<2>(rb);
  const Eigen::MatrixXd& P = m.covariance;
  const Mat2 S = P.block<2, 2>(ra, ra) + P.block<2, 2>(rb, rb) - P.block<2, 2>(ra, rb) - P.block<2, 2>(rb, ra);
  const Eigen::LLT<Mat2> llt(0.5 * (S + S.transpose()));
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  return delta.dot(llt.solve(delta));
}

}  // namespace

double correspondenceDistance(const SlamFilter& filter, int a, int b, MarginalMode mode) {
  const int ids[2] = {a, b};
  return correspondenceD2(filter.marginal(ids, false, mode), 0, 2);
}

namespace {

/// sqrt(lambda_max) of a 2x2 covariance, in closed form.
double worstSigma(const Mat2& C) {
  const double a = C(0, 0), d = C(1, 1), b = 0.5 * (C(0, 1) + C(1, 0));
  const double half = 0.5 * (a + d), gap = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return std::sqrt(std::max(0.0, half + gap));
}

struct Provisional {
  std::size_t born = 0;  // the scan (Impl::scans) that started it
  int sightings = 1;
  double score = 0.0;  // ConfirmRule::Score: the track's log-likelihood ratio since its first sighting
  // ProvisionalPlace::Held: the landmark's own estimate outside the filter, y = mean +
  // lever * e_x + e, its error e_x shared with the pose's (the error of the pose that first
  // saw it, taken as the current pose's: the lever is the inverse sensor model's pose
  // Jacobian there) and its own e ~ N(0, covariance).
  bool held = false;
  Vec2 mean = Vec2::Zero();
  Mat2 covariance = Mat2::Zero();
  Mat23 lever = Mat23::Zero();
};

}  // namespace

struct Associator::Impl {
  AssociationOptions options;
  AssociationCounts counts;
  double accept_d2 = 0.0, new_d2 = 0.0, merge_d2 = 0.0;
  CandidateGrid grid;
  double slack = 0.0;
  int next_id = 0;
  // Per landmark: how many of its observations carried each truth id (kUnknownLandmark
  // counts those without one). The label of a landmark is its most frequent truth id.
  std::unordered_map<int, std::unordered_map<int, std::size_t>> seen_truths;
  std::unordered_map<int, int> label;  // set by finish()
  std::unordered_set<int> duplicates;  // set by finish(): landmarks with an older one's label
  std::unordered_map<int, Provisional> provisional;
  std::vector<int> touched;  // landmarks to re-index at the next scan
  std::vector<ScanDecision> decisions;  // Associator::lastScan()
  std::vector<LandmarkMerge> merges;    // Associator::lastMerges()
  std::vector<int> started;  // landmarks the last scan started in the filter
  std::size_t refresh_cursor = 0;
  std::size_t scans = 0;  // steps with observations so far
  // ConfirmRule::Score: the sensor's footprint, where in measurement space the observations
  // so far lie (footprint.hpp).
  SensorFootprint footprint;
  std::size_t explained = 0;  // observations paired with a confirmed landmark so far
  std::vector<double> joint_gates;  // JCBB's chi-square(2k) gates (ScanProblem::joint_gates)
  // What the last scan's observations changed, for discardScan(): the counts and next id
  // before them, the landmarks they started, each provisional entry they touched as it was
  // (none: they started it), the truth tallies they added, and how long touched and started
  // were.
  struct ScanRecord {
    bool open = false;
    AssociationCounts counts;
    int next_id = 0;
    std::vector<int> fresh;
    std::vector<std::pair<int, std::optional<Provisional>>> provisional;
    std::unordered_set<int> recorded;  // the ids in `provisional`
    std::vector<std::pair<int, int>> tallies;
    std::size_t touched = 0, started = 0;
    SensorFootprint footprint;
  } scan_record;

  bool scored() const { return options.confirm_rule == ConfirmRule::Score; }
  /// Whether a new landmark starts provisional (count 1: confirmed at once).
  bool provisionalStart() const { return scored() || options.confirm > 1; }
  bool confirmed(const Provisional& p) const {
    return scored() ? p.score >= trackConfirmScore() : p.sightings >= options.confirm;
  }

  void recordProvisional(int id) {
    if (!scan_record.recorded.insert(id).second) return;  // the first record is the state before the scan
    const auto p = provisional.find(id);
    scan_record.provisional.emplace_back(id, p == provisional.end() ? std::nullopt : std::optional<Provisional>(p->second));
  }

  void discardScan() {
    if (!scan_record.open) return;
    scan_record.open = false;
    // Newest first, so each entry returns to its state before the scan.
    for (auto it = scan_record.provisional.rbegin(); it != scan_record.provisional.rend(); ++it) {
      const auto& [id, before] = *it;
      if (before) {
        provisional[id] = *before;
      } else {
        provisional.erase(id);
      }
    }
    for (const auto& [id, truth] : scan_record.tallies) {
      auto& per_truth = seen_truths[id];
      if (--per_truth[truth] == 0) per_truth.erase(truth);
      if (per_truth.empty()) seen_truths.erase(id);
    }
    // The landmarks the scan started are gone: from the index, and their ids are free again
    // (next_id skips those a caller's map held before, which stay indexed).
    for (int id : scan_record.fresh) grid.remove(id);
    const double seconds = counts.seconds;
    counts = scan_record.counts;
    counts.seconds = seconds;
    next_id = scan_record.next_id;
    touched.resize(scan_record.touched);
    started.resize(scan_record.started);
    footprint = scan_record.footprint;
    // `explained` stays, as counts.observations and scans do: the clutter estimate's ratio.
  }

  /// The marginal the gates use: the option's, or the filter's own (auto).
  MarginalMode gateOf(const SlamFilter& filter) const { return options.marginal.value_or(filter.gateMarginal()); }

  void forget(int id) {
    grid.remove(id);
    provisional.erase(id);
    const auto it = seen_truths.find(id);
    if (it != seen_truths.end()) {
      for (const auto& [truth, n] : it->second) counts.in_removed_landmarks += n;
      seen_truths.erase(it);
    }
  }

  /// The landmark's most frequent truth id (the smaller id on a tie), or kUnknownLandmark.
  int majority(int id) const {
    const auto it = seen_truths.find(id);
    int best = kUnknownLandmark;
    std::size_t most = 0;
    if (it == seen_truths.end()) return best;
    for (const auto& [truth, n] : it->second) {
      if (truth >= 0 && (n > most || (n == most && truth < best))) {
        best = truth;
        most = n;
      }
    }
    return best;
  }

  /// Re-indexes the landmarks observed last scan and `refresh` others (cyclically), then
  /// merges duplicates among those observed last scan. A landmark's spread is from the last
  /// scan that offered it (or started it) and its indexed mean from that scan's update or
  /// later, so a later move of its mean within that covariance - a loop closure - still
  /// leaves it in reach; the slack covers moves beyond what the covariance claimed.
  void refreshIndex(SlamFilter& filter) {
    if (!grid.ready()) {
      touched.clear();
      return;
    }
    for (int id : touched) {
      if (filter.hasLandmark(id)) {
        grid.put(id, filter.landmark(id));
      } else if (const auto p = provisional.find(id); p != provisional.end() && p->second.held) {
        grid.put(id, p->second.mean);
      }
    }
    const auto& ids = filter.landmarkIds();
    const std::size_t n = std::min<std::size_t>(ids.size(), static_cast<std::size_t>(std::max(0, options.refresh)));
    for (std::size_t r = 0; r < n; ++r) {
      refresh_cursor = (refresh_cursor + 1) % ids.size();
      grid.put(ids[refresh_cursor], filter.landmark(ids[refresh_cursor]));
    }
    mergeDuplicates(filter, touched);
    touched.clear();
  }

  /// Merges every landmark observed last scan into an older one nearby that the
  /// correspondence test cannot tell from it (never two seen in the same scan).
  void mergeDuplicates(SlamFilter& filter, const std::vector<int>& last_scan) {
    if (merge_d2 <= 0.0 || !grid.ready()) return;
    // The pairs to test, and one joint marginal of every landmark in them.
    std::vector<std::pair<int, int>> pairs;
    std::vector<int> ids, near;
    std::unordered_map<int, Eigen::Index> row;
    const auto add = [&](int id) {
      if (row.emplace(id, 2 * static_cast<Eigen::Index>(ids.size())).second) ids.push_back(id);
    };
    for (int id : last_scan) {
      if (!filter.hasLandmark(id)) continue;
      // Within the merge gate's reach of either mean: sqrt(chi2) (sigma_id + sigma_other).
      const double scale = std::sqrt(merge_d2);
      grid.query(filter.landmark(id), slack + scale * grid.spread(id), scale, near);
      for (int other : near) {
        if (other == id || !filter.hasLandmark(other) ||
            std::find(last_scan.begin(), last_scan.end(), other) != last_scan.end()) {
          continue;
        }
        pairs.emplace_back(id, other);
        add(id);
        add(other);
      }
    }
    if (pairs.empty()) return;
    const MarginalMode gate = gateOf(filter);
    const Marginal joint = filter.marginal(ids, false, gate);
    bool merged_any = false;
    int done = -1;  // `id` whose merge ended its pairs
    for (const auto& [id, other] : pairs) {
      if (id == done || !filter.hasLandmark(id) || !filter.hasLandmark(other)) continue;
      // After a merge the joint marginal is stale: the rest are tested one by one.
      const double d2 = merged_any ? correspondenceDistance(filter, id, other, gate)
                                   : correspondenceD2(joint, row.at(id), row.at(other));
      if (d2 > merge_d2) continue;
      const int keep = std::min(id, other), drop = std::max(id, other);  // the older stays
      filter.mergeLandmarks(keep, drop);
      merges.push_back({keep, drop});
      for (const auto& [truth, n] : seen_truths[drop]) seen_truths[keep][truth] += n;
      seen_truths.erase(drop);
      const auto pd = provisional.find(drop);
      const auto pk = provisional.find(keep);
      if (pk != provisional.end()) {  // at most `confirm`: no overflow whatever confirm is
        const std::int64_t total =
            std::int64_t{pk->second.sightings} + (pd != provisional.end() ? pd->second.sightings : options.confirm);
        pk->second.sightings = static_cast<int>(std::min<std::int64_t>(total, options.confirm));
        if (pd == provisional.end()) {
          provisional.erase(pk);  // merged with a confirmed landmark: confirmed, whatever the rule
        } else {
          // The score: each scan saw at most one of the two, and the other missed it there,
          // so their sum counts those misses twice; the better of either and the sum.
          pk->second.score = std::max({pk->second.score, pd->second.score, pk->second.score + pd->second.score});
          if (confirmed(pk->second)) provisional.erase(pk);
        }
      }
      forget(drop);
      grid.put(keep, filter.landmark(keep));
      ++counts.merged;
      merged_any = true;
      done = id;  // `id` may be gone: on to the next
    }
  }

  /// ConfirmRule::Score: grows the footprint by the scan's observations, counts those paired
  /// with confirmed landmarks, and returns log(lambda), the clutter density's: the option's,
  /// or the observations so far that no confirmed landmark explained, per scan, over the
  /// footprint's volume (an upper bound: a landmark's sightings before it is confirmed count
  /// as clutter). None while the footprint has no volume (the scan then changes no score).
  std::optional<double> scanClutter(const MeasurementModel& sensor, const std::vector<Observation>& observations,
                                    const std::vector<int>& pairing) {
    for (std::size_t i = 0; i < observations.size(); ++i) {
      footprint.add(sensor, observations[i].z);
      if (pairing[i] >= 0 && provisional.count(pairing[i]) == 0) ++explained;
    }
    const double volume = footprint.volume();
    if (!(volume > 0.0) || !std::isfinite(volume)) return std::nullopt;
    double lambda = options.clutter_density;
    if (lambda == 0.0) {
      const double unexplained = static_cast<double>(counts.observations - explained);
      lambda = std::max(unexplained, 1.0) / (static_cast<double>(scans) * volume);
    }
    if (!(lambda > 0.0) || !std::isfinite(lambda)) return std::nullopt;  // a footprint of no usable volume
    return std::log(lambda);
  }

  /// The track score's misses: each provisional landmark started before this scan and not
  /// seen in it, whose predicted measurement from the pose mean lies in the footprint, adds
  /// log(1 - P_D).
  void scoreMisses(const SlamFilter& filter, const Pose2& x, const std::vector<int>& pairing) {
    const MeasurementModel& sensor = filter.sensorModel();
    const double miss = trackMissScore(options.detection_probability);
    const std::unordered_set<int> seen(pairing.begin(), pairing.end());
    for (auto& [id, p] : provisional) {
      if (p.born == scans || seen.count(id) > 0) continue;
      const Vec2 y = p.held ? p.mean : filter.landmark(id);
      if (!footprint.contains(sensor, sensor.predict(x, y))) continue;
      recordProvisional(id);
      p.score += miss;
    }
  }

  /// A held landmark's Kalman update from one sighting, on its own error e (covariance C):
  /// K = C J_y^T S^-1 with S from the scan's joint marginal, the shared pose error in it.
  static void updateHeld(Provisional& p, const MeasurementModel& sensor, const Marginal& joint, Eigen::Index row,
                         const Observation& z) {
    Mat2 J_y;
    const PredictedMeasurement pm = predictFromMarginal(sensor, joint, row, sensor.noise(z), nullptr, &J_y);
    const Eigen::LLT<Mat2> llt(pm.S);
    if (llt.info() != Eigen::Success) return;
    const Mat2 K = llt.solve(J_y * p.covariance).transpose();  // C J_y^T S^-1
    p.mean += K * sensor.residual(z.z, pm.z);
    const Mat2 C = (Mat2::Identity() - K * J_y) * p.covariance;
    p.covariance = 0.5 * (C + C.transpose());
  }

  /// The landmarks the last scan started in the filter (new ones, and held ones it confirmed)
  /// but the filter does not hold: its update failed (all or nothing) and the caller went
  /// on. They are forgotten as never started. (The scan's sightings of other provisional
  /// landmarks stay counted.)
  void dropUnapplied(const SlamFilter& filter) {
    for (int id : started) {
      if (filter.hasLandmark(id)) continue;
      grid.remove(id);
      provisional.erase(id);
      seen_truths.erase(id);
      --counts.new_landmarks;
    }
    started.clear();
  }

  void expireProvisional(SlamFilter& filter, std::size_t scan) {
    std::vector<int> expired;
    for (const auto& [id, p] : provisional) {
      const bool rejected = scored() && p.score <= trackDeleteScore();  // the track score's test
      if (rejected || scan > p.born + static_cast<std::size_t>(options.window)) expired.push_back(id);
    }
    std::sort(expired.begin(), expired.end());
    for (int id : expired) {
      if (!provisional.at(id).held && filter.hasLandmark(id)) filter.removeLandmark(id);
      forget(id);
      ++counts.provisional_removed;
    }
  }
};

Associator::Associator(const AssociationOptions& options) : impl_(std::make_unique<Impl>()) {
  checkAssociationOptions(options);  // each range as its flag has it
  const AssociationOptions& o = options;
  if (!(o.accept > 0.0) || o.new_landmark < o.accept) {  // each below 1: the table's range
    throw InvalidArgument("association: gates need 0 < accept <= new_landmark < 1 (chi-square probabilities)");
  }
  // Seen once a scan at most, a landmark born at scan b has its confirm-th sighting at scan
  // b + confirm - 1 at the earliest, and expires after scan b + window.
  if (o.method != AssociationMethod::Known && o.confirm_rule == ConfirmRule::Score && o.window < 1) {
    throw InvalidArgument("association: window 0 (--window) can never confirm a landmark by its track score (confirm-rule "
                          "score needs a window of at least 1 scan)");
  }
  if (o.method != AssociationMethod::Known && o.confirm_rule == ConfirmRule::Count && o.confirm > 1 &&
      o.window < o.confirm - 1) {
    throw InvalidArgument("association: window " + std::to_string(o.window) + " (--window) can never confirm a landmark (confirm " +
                          std::to_string(o.confirm) + " needs a window of at least " + std::to_string(o.confirm - 1) +
                          " scans)");
  }
  impl_->options = options;
  const auto chi2 = [](double p) { return -2.0 * std::log1p(-p); };  // chi-square(2) quantile, closed form
  impl_->accept_d2 = chi2(o.accept);
  impl_->new_d2 = chi2(o.new_landmark);
  impl_->merge_d2 = o.merge > 0.0 ? chi2(o.merge) : 0.0;
}

Associator::~Associator() = default;
Associator::Associator(Associator&&) noexcept = default;
Associator& Associator::operator=(Associator&&) noexcept = default;

void Associator::discardScan() { impl_->discardScan(); }

const AssociationCounts& Associator::counts() const { return impl_->counts; }
std::span<const ScanDecision> Associator::lastScan() const { return impl_->decisions; }
std::span<const LandmarkMerge> Associator::lastMerges() const { return impl_->merges; }

std::string_view scanOutcomeName(ScanDecision::Outcome o) {
  switch (o) {
    case ScanDecision::Outcome::Matched: return "matched";
    case ScanDecision::Outcome::New: return "new";
    case ScanDecision::Outcome::Ambiguous: return "ambiguous";
  }
  return "?";
}
const AssociationOptions& Associator::options() const { return impl_->options; }
int Associator::truthOf(int id) const {
  const auto it = impl_->label.find(id);
  return it != impl_->label.end() ? it->second : impl_->majority(id);
}
bool Associator::isDuplicate(int id) const { return impl_->duplicates.count(id) != 0; }

void Associator::associate(SlamFilter& filter, std::size_t /*k*/, std::vector<Observation>& observations) {
  Impl& s = *impl_;
  const auto start = std::chrono::steady_clock::now();
  s.decisions.clear();
  s.merges.clear();
  if (s.options.method == AssociationMethod::Known) {
    s.counts.observations += observations.size();
    if (s.options.drop_unlabelled) {
      const auto unlabelled = [](const Observation& z) { return z.landmark == kUnknownLandmark; };
      const auto first = std::remove_if(observations.begin(), observations.end(), unlabelled);
      s.counts.unlabelled_dropped += static_cast<std::size_t>(observations.end() - first);
      observations.erase(first, observations.end());
    }
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (observations[i].landmark == kUnknownLandmark) {
        throw ModelError("association known: observation " + std::to_string(i) +
                         " has no landmark id (choose association method nn or jcbb, --association, or drop "
                         "it: drop_unlabelled, --drop-unlabelled)");
      }
    }
    return;
  }
  // The data's ids are hidden from the filter: kept as the truth that scores the association.
  for (Observation& z : observations) {
    if (z.truth == kUnknownLandmark) z.truth = z.landmark;
    z.landmark = kUnknownLandmark;
  }
  s.scan_record.open = false;  // the filter took the last scan, or the caller let it go
  s.counts.observations += observations.size();
  s.dropUnapplied(filter);
  s.refreshIndex(filter);
  if (observations.empty()) return;  // a step without a scan: nothing to associate, no scan counted
  ++s.scans;
  s.expireProvisional(filter, s.scans);

  const MeasurementModel& sensor = filter.sensorModel();
  const MarginalMode gate = s.gateOf(filter);
  const Marginal pose = filter.marginal({}, true, gate);
  const Pose2 x = pose.mean.head<3>();
  // Each observation's world point, and how far from it the new-landmark gate can reach:
  // sqrt(new_d2 * lambda_max(J_x P J_x^T + J_z R J_z^T)) of the inverse model.
  std::vector<Vec2> point(observations.size());
  std::vector<Mat2> spread(observations.size());  // the point's covariance given the pose
  std::vector<Mat23> lever(observations.size());  // the point's Jacobian in the pose
  std::vector<double> radius(observations.size());
  std::vector<double> sigma(observations.size());  // sqrt(lambda_max) of the point's covariance
  for (std::size_t i = 0; i < observations.size(); ++i) {
    Mat23& J_x = lever[i];
    Mat2 J_z;
    point[i] = sensor.inverse(x, observations[i].z, &J_x, &J_z);
    const Mat2 W = J_x * pose.covariance * J_x.transpose() + J_z * sensor.noise(observations[i]) * J_z.transpose();
    const Mat2 V = J_z * sensor.noise(observations[i]) * J_z.transpose();
    spread[i] = 0.5 * (V + V.transpose());
    sigma[i] = worstSigma(W);
    radius[i] = std::sqrt(s.new_d2) * sigma[i];
    if (!point[i].allFinite() || !W.allFinite() || !std::isfinite(radius[i])) {  // worstSigma's max(0, NaN) is 0
      throw ModelError("association: observation " + std::to_string(i) + " has no finite position in the map");
    }
  }
  if (!s.grid.ready()) {
    double r0 = 0.0;
    for (double r : radius) r0 = std::max(r0, r);
    if (r0 > 0.0) {
      s.slack = s.options.slack > 0.0 ? s.options.slack : r0;
      s.grid.setCell(2.0 * r0 + s.slack);
      for (int id : filter.landmarkIds()) s.grid.put(id, filter.landmark(id));  // a map the filter started with
    }
  }

  ScanProblem scan;
  scan.filter = &filter;
  scan.sensor = &sensor;
  scan.observations = &observations;
  scan.accept_d2 = s.accept_d2;
  scan.accept_probability = s.options.accept;
  scan.marginal = gate;
  scan.joint_gates = &s.joint_gates;
  scan.compatible.resize(observations.size());
  std::vector<double> nearest(observations.size(), std::numeric_limits<double>::infinity());
  // Each observation's candidates from the grid; one joint marginal of the pose and all of
  // them serves every pairing of the scan (and JCBB's joint test).
  // Held provisional landmarks join it after the filter's, uncorrelated with anything.
  std::vector<std::vector<int>> found(observations.size());
  std::vector<int> ids, held;
  for (std::size_t i = 0; i < observations.size() && s.grid.ready(); ++i) {
    // The observed point's reach plus each landmark's own: the difference of the two has a
    // standard deviation of at most the sum of theirs along any axis.
    s.grid.query(point[i], radius[i] + s.slack, std::sqrt(s.new_d2), found[i]);
    for (int id : found[i]) {
      const auto p = s.provisional.find(id);
      std::vector<int>& list = p != s.provisional.end() && p->second.held ? held : ids;
      if (std::find(list.begin(), list.end(), id) == list.end()) list.push_back(id);
    }
  }
  scan.joint = ids.empty() ? pose : filter.marginal(ids, true, gate);
  for (std::size_t j = 0; j < ids.size(); ++j) {
    const Eigen::Index r = 3 + 2 * static_cast<Eigen::Index>(j);
    scan.column[ids[j]] = r;
    s.grid.setSpread(ids[j], worstSigma(scan.joint.covariance.block<2, 2>(r, r)));
  }
  if (!held.empty()) {
    // Rows of y = mean + lever e_x + e: Cov(y, .) = lever Cov(x, .), Cov(y) = lever P_xx lever^T + C.
    const Eigen::Index n0 = scan.joint.mean.size(), n = n0 + 2 * static_cast<Eigen::Index>(held.size());
    const Eigen::MatrixXd pose_rows = scan.joint.covariance.topRows(3);
    Eigen::MatrixXd L(n - n0, 3);
    for (std::size_t j = 0; j < held.size(); ++j) L.middleRows<2>(2 * static_cast<Eigen::Index>(j)) = s.provisional.at(held[j]).lever;
    scan.joint.mean.conservativeResize(n);
    Eigen::MatrixXd& P = scan.joint.covariance;
    P.conservativeResize(n, n);
    P.bottomLeftCorner(n - n0, n0) = L * pose_rows;
    P.topRightCorner(n0, n - n0) = P.bottomLeftCorner(n - n0, n0).transpose();
    P.bottomRightCorner(n - n0, n - n0) = L * pose_rows.leftCols<3>() * L.transpose();
    for (std::size_t j = 0; j < held.size(); ++j) {
      const Eigen::Index r = n0 + 2 * static_cast<Eigen::Index>(j);
      const Provisional& p = s.provisional.at(held[j]);
      scan.joint.mean.segment<2>(r) = p.mean;
      P.block<2, 2>(r, r) += p.covariance;
      scan.column[held[j]] = r;
      s.grid.setSpread(held[j], worstSigma(P.block<2, 2>(r, r)));
    }
  }
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const Mat2 R = sensor.noise(observations[i]);
    for (int id : found[i]) {
      const PredictedMeasurement pm = predictFromMarginal(sensor, scan.joint, scan.column.at(id), R);
      const Vec2 nu = sensor.residual(observations[i].z, pm.z);
      const Eigen::LLT<Mat2> llt(pm.S);
      if (llt.info() != Eigen::Success) continue;
      const double d2 = nu.dot(llt.solve(nu));
      nearest[i] = std::min(nearest[i], d2);
      if (d2 <= s.accept_d2) scan.compatible[i].push_back({static_cast<int>(i), id, d2});
    }
    // The provisional list is a second resort (Probabilistic Robotics §12.7): an observation
    // compatible with a confirmed landmark is not offered the provisional ones.
    auto& c = scan.compatible[i];
    const auto provisional = [&](const Pairing& p) { return s.provisional.count(p.landmark) > 0; };
    if (std::any_of(c.begin(), c.end(), [&](const Pairing& p) { return !provisional(p); })) {
      c.erase(std::remove_if(c.begin(), c.end(), provisional), c.end());
    }
  }
  bool truncated = false;
  const std::vector<int> pairing = s.options.method == AssociationMethod::Jcbb
                                       ? assignJcbb(scan, s.options.jcbb_nodes, &truncated)
                                       : assignNearestNeighbour(scan);
  if (truncated) ++s.counts.jcbb_truncated;

  // Apply: matched, new or dropped (scored against the truth at finish()); recorded for
  // discardScan().
  Impl::ScanRecord& record = s.scan_record;
  record.open = true;
  record.counts = s.counts;
  record.next_id = s.next_id;
  record.fresh.clear();
  record.provisional.clear();
  record.recorded.clear();
  record.tallies.clear();
  record.touched = s.touched.size();
  record.started = s.started.size();
  record.footprint = s.footprint;
  const std::optional<double> log_clutter = s.scored() ? s.scanClutter(sensor, observations, pairing) : std::nullopt;
  std::vector<Observation> kept;
  kept.reserve(observations.size());
  s.decisions.assign(observations.size(), ScanDecision{});
  for (std::size_t i = 0; i < observations.size(); ++i) {
    Observation z = observations[i];
    bool apply = true;  // false: the sighting of a held landmark, kept out of the filter
    ScanDecision& decision = s.decisions[i];
    decision.d2 = nearest[i];
    if (pairing[i] >= 0) {
      z.landmark = pairing[i];
      decision.outcome = ScanDecision::Outcome::Matched;
      for (const Pairing& p : scan.compatible[i]) {
        if (p.landmark == z.landmark) decision.d2 = p.d2;
      }
      if (const auto p = s.provisional.find(z.landmark); p != s.provisional.end()) {
        s.recordProvisional(z.landmark);
        Provisional& track = p->second;
        ++track.sightings;
        if (log_clutter) {  // the track score: log(P_D N(nu; 0, S) / lambda)
          const PredictedMeasurement pm = predictFromMarginal(sensor, scan.joint, scan.column.at(z.landmark), sensor.noise(z));
          track.score += trackSightingScore(sensor.residual(z.z, pm.z), pm.S, s.options.detection_probability, *log_clutter);
        }
        const bool confirming = s.confirmed(track);
        if (track.held) {
          s.updateHeld(track, sensor, scan.joint, scan.column.at(z.landmark), z);
          apply = confirming;
          // Confirmed: it enters the filter as one sighting of its fused estimate from here,
          // z = h(x, mean), with noise J_y C J_y^T: every sighting's information, once.
          if (apply) {
            s.started.push_back(z.landmark);  // in the filter from this update on (if it takes it)
            Mat23 J_x;
            Mat2 J_y;
            z.z = sensor.predict(x, track.mean, &J_x, &J_y);
            const Mat2 R = J_y * track.covariance * J_y.transpose();
            z.noise = 0.5 * (R + R.transpose());
          }
        }
        if (confirming) {
          s.provisional.erase(p);
        } else {
          decision.provisional = true;
        }
      }
    } else if (nearest[i] > s.new_d2) {
      decision.outcome = ScanDecision::Outcome::New;
      while (filter.hasLandmark(s.next_id)) ++s.next_id;  // ids the filter held before (a caller's map)
      z.landmark = s.next_id++;
      record.fresh.push_back(z.landmark);
      ++s.counts.new_landmarks;
      if (s.provisionalStart()) {
        s.recordProvisional(z.landmark);
        const bool hold = s.options.provisional == ProvisionalPlace::Held;
        s.provisional[z.landmark] = Provisional{s.scans, 1, 0.0, hold, point[i], spread[i], lever[i]};
        apply = !hold;
        decision.provisional = true;
      }
      if (apply) s.started.push_back(z.landmark);
      s.grid.setSpread(z.landmark, sigma[i]);  // its covariance is the point's
    } else {
      ++s.counts.ambiguous_dropped;
      continue;
    }
    decision.landmark = z.landmark;
    decision.applied = apply;
    const int truth = z.truth < 0 ? kUnknownLandmark : z.truth;
    ++s.seen_truths[z.landmark][truth];
    record.tallies.emplace_back(z.landmark, truth);
    s.touched.push_back(z.landmark);
    if (apply) kept.push_back(z);
  }
  if (log_clutter) s.scoreMisses(filter, x, pairing);
  observations = std::move(kept);
  s.counts.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Associator::finish(SlamFilter& filter, const std::atomic<bool>* stop) {
  Impl& s = *impl_;
  s.scan_record.open = false;
  s.dropUnapplied(filter);
  AssociationCounts& c = s.counts;
  // Landmarks still provisional were not confirmed: the final map holds confirmed ones only
  // (a smoother, which cannot remove, keeps them and counts them).
  std::vector<int> unconfirmed;
  for (const auto& [id, p] : s.provisional) unconfirmed.push_back(id);
  std::sort(unconfirmed.begin(), unconfirmed.end());
  c.provisional_final = 0;
  for (int id : unconfirmed) {
    if (s.provisional.at(id).held) {
      s.forget(id);
      ++c.provisional_removed;
      continue;
    }
    // A removal may cost much in a dense map (the SEIF's fill-in among a landmark's links):
    // an interrupted run keeps the rest (provisional_final).
    if (filter.smoother() || (stop != nullptr && stop->load(std::memory_order_relaxed))) {
      ++c.provisional_final;
      continue;
    }
    if (filter.hasLandmark(id)) filter.removeLandmark(id);
    s.forget(id);
    ++c.provisional_removed;
  }
  c.landmarks_final = filter.landmarkIds().size();
  if (s.options.method == AssociationMethod::Known) return;
  c.scored = c.correct = c.wrong = c.unlabelled = c.unlabelled_matched = 0;
  c.spurious_landmarks = c.duplicate_landmarks = 0;
  s.label.clear();
  s.duplicates.clear();
  std::unordered_set<int> labelled;
  // The older landmark (the smaller id) keeps a shared label; the map's order is not the
  // landmarks' age once removals have moved slots.
  std::vector<int> by_age = filter.landmarkIds();
  std::sort(by_age.begin(), by_age.end());
  for (int id : by_age) {
    const int label = s.majority(id);
    const bool duplicate = label >= 0 && !labelled.insert(label).second;
    s.label[id] = label;
    if (label < 0) ++c.spurious_landmarks;
    if (duplicate) {
      s.duplicates.insert(id);
      ++c.duplicate_landmarks;
    }
    const auto it = s.seen_truths.find(id);
    if (it == s.seen_truths.end()) continue;
    for (const auto& [truth, n] : it->second) {
      if (truth < 0) {
        c.unlabelled += n;
        if (label >= 0) c.unlabelled_matched += n;
        continue;
      }
      c.scored += n;
      (truth == label && !duplicate ? c.correct : c.wrong) += n;
    }
  }
}

// ---------------------------------------------------------------- checkpoints ---------
// Every map is written by ascending id, so equal states write equal bytes; what is derived
// (the gates' distances, the grid's cells, JCBB's cached joint gates) is rebuilt.

namespace {

constexpr std::size_t AssociationCounts::*kCountFields[] = {
    &AssociationCounts::observations,        &AssociationCounts::scored,
    &AssociationCounts::correct,             &AssociationCounts::wrong,
    &AssociationCounts::unlabelled,          &AssociationCounts::unlabelled_matched,
    &AssociationCounts::in_removed_landmarks, &AssociationCounts::new_landmarks,
    &AssociationCounts::ambiguous_dropped,   &AssociationCounts::unlabelled_dropped,
    &AssociationCounts::provisional_removed, &AssociationCounts::provisional_final,
    &AssociationCounts::merged,              &AssociationCounts::jcbb_truncated,
    &AssociationCounts::landmarks_final,     &AssociationCounts::spurious_landmarks,
    &AssociationCounts::duplicate_landmarks,
};
// A count added to AssociationCounts must be added above (seconds is written apart).
static_assert(sizeof(AssociationCounts) == std::size(kCountFields) * sizeof(std::size_t) + sizeof(double));

template <class Map>
std::vector<typename Map::key_type> sortedKeys(const Map& map) {
  std::vector<typename Map::key_type> keys;
  keys.reserve(map.size());
  for (const auto& entry : map) keys.push_back(entry.first);
  std::sort(keys.begin(), keys.end());
  return keys;
}

void writeIds(ArchiveWriter& w, const std::vector<int>& ids) {
  w.count(ids.size());
  for (int id : ids) w.i64(id);
}

// Version 3: the footprint as clusters per axis (footprint.hpp) instead of a box.
constexpr std::string_view kStateSection = "associator v3";

int readId(ArchiveReader& r, const char* what) {
  return static_cast<int>(r.i64In(what, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
}

std::vector<int> readIds(ArchiveReader& r, const char* what) {
  std::vector<int> ids(r.count(what, 9));
  for (int& id : ids) id = readId(r, what);
  return ids;
}

}  // namespace

std::string Associator::saveState() const {
  const Impl& s = *impl_;
  ArchiveWriter w;
  w.section(kStateSection);
  w.count(associationOptions().size());
  for (const AssociationOption& o : associationOptions()) {
    w.str(o.key);
    w.str(o.get(s.options));
  }
  for (const auto field : kCountFields) w.u64(s.counts.*field);
  w.f64(s.counts.seconds);
  w.f64(s.grid.cell());
  const auto positions = s.grid.positions();
  w.count(positions.size());
  for (const auto& [id, y] : positions) {
    w.i64(id);
    w.fixed(y);
  }
  const auto spreads = s.grid.spreads();
  w.count(spreads.size());
  for (const auto& [id, sigma] : spreads) {
    w.i64(id);
    w.f64(sigma);
  }
  w.f64(s.slack);
  w.i64(s.next_id);
  w.count(s.seen_truths.size());
  for (int id : sortedKeys(s.seen_truths)) {
    const auto& tally = s.seen_truths.at(id);
    w.i64(id);
    w.count(tally.size());
    for (int truth : sortedKeys(tally)) {
      w.i64(truth);
      w.u64(tally.at(truth));
    }
  }
  w.count(s.provisional.size());
  for (int id : sortedKeys(s.provisional)) {
    const Provisional& p = s.provisional.at(id);
    w.i64(id);
    w.u64(p.born);
    w.i64(p.sightings);
    w.f64(p.score);
    w.u64(p.held ? 1 : 0);
    w.fixed(p.mean);
    w.fixed(p.covariance);
    w.fixed(p.lever);
  }
  writeIds(w, s.touched);
  writeIds(w, s.started);
  w.u64(s.refresh_cursor);
  w.u64(s.scans);
  s.footprint.save(w);
  w.u64(s.explained);
  return w.bytes();
}

Associator Associator::restoreState(std::string_view bytes, const std::string& name) {
  ArchiveReader r(bytes, name);
  // Version 2 added the track score (each provisional landmark's score, the footprint, the
  // explained observations); a version-1 state restores with none of them (its rule: count).
  // Version 3 holds the footprint as clusters; a version-2 box becomes one per axis.
  int version = 3;
  try {
    r.section(kStateSection);
  } catch (const DataError&) {
    try {
      r.section("associator v2");
      version = 2;
    } catch (const DataError&) {
      r.section("associator");
      version = 1;
    }
  }
  const bool scored_state = version >= 2;
  AssociationOptions options;
  const std::size_t n_options = r.count("association options", 2);
  for (std::size_t i = 0; i < n_options; ++i) {
    const std::string key = r.str("association option");
    const std::string value = r.str("association option value");
    const auto table = associationOptions();
    const auto o = std::find_if(table.begin(), table.end(), [&](const AssociationOption& x) { return x.key == key; });
    if (o == table.end()) r.fail("unknown association option '" + key + "'");
    try {
      o->set(options, value);
    } catch (const InvalidArgument& e) {
      r.fail(e.what());
    }
  }
  std::optional<Associator> restored;
  try {
    restored.emplace(options);
  } catch (const InvalidArgument& e) {
    r.fail(e.what());
  }
  Impl& s = *restored->impl_;
  for (const auto field : kCountFields) s.counts.*field = static_cast<std::size_t>(r.u64("association count"));
  s.counts.seconds = r.f64("association seconds");
  const double cell = r.f64("grid cell");
  if (!(cell >= 0.0) || !std::isfinite(cell)) r.fail("the grid's cell is not a finite length");
  s.grid.setCell(cell);
  const std::size_t n_positions = r.count("grid positions", 2 * 9 + 9);
  if (n_positions > 0 && !s.grid.ready()) r.fail("landmarks indexed in a grid without cells");
  for (std::size_t i = 0; i < n_positions; ++i) {
    const int id = readId(r, "grid landmark");
    Vec2 y;
    r.fixed("grid position", y, true);
    s.grid.put(id, y);
  }
  const std::size_t n_spreads = r.count("grid spreads", 2 * 9);
  for (std::size_t i = 0; i < n_spreads; ++i) {
    const int id = readId(r, "spread landmark");
    const double sigma = r.f64("spread");  // +inf: a landmark whose covariance was unbounded
    if (!(sigma >= 0.0)) r.fail("landmark " + std::to_string(id) + "'s spread is not a length");
    s.grid.setSpread(id, sigma);
  }
  s.slack = r.f64("slack");
  if (!(s.slack >= 0.0) || !std::isfinite(s.slack)) r.fail("the slack is not a finite length");
  s.next_id = static_cast<int>(r.i64In("next landmark id", 0, std::numeric_limits<int>::max() - 1));
  const std::size_t n_tallies = r.count("truth tallies", 2 * 9);
  for (std::size_t i = 0; i < n_tallies; ++i) {
    auto& tally = s.seen_truths[readId(r, "tallied landmark")];
    const std::size_t n = r.count("truth tally", 2 * 9);
    for (std::size_t k = 0; k < n; ++k) {
      const int truth = readId(r, "truth id");
      tally[truth] = static_cast<std::size_t>(r.u64("truth count"));
    }
  }
  const std::size_t n_provisional = r.count("provisional landmarks", 4 * 9 + 12 * 9);
  for (std::size_t i = 0; i < n_provisional; ++i) {
    const int id = readId(r, "provisional landmark");
    Provisional p;
    p.born = static_cast<std::size_t>(r.u64("provisional birth scan"));
    if (options.confirm_rule == ConfirmRule::Count) {
      // Provisional while seen fewer than `confirm` times (associate() erases it at confirm).
      if (options.confirm <= 1) r.fail("a provisional landmark, but every landmark is confirmed at once (confirm 1)");
      p.sightings = static_cast<int>(r.i64In("provisional sightings", 1, options.confirm - 1));
    } else {
      // Seen once a scan at most, from its first scan to `window` scans after it.
      // (A merge adds two counts, capped at `confirm`.)
      const std::int64_t most = std::min<std::int64_t>(std::max<std::int64_t>(std::int64_t{options.window} + 1, options.confirm),
                                                       std::numeric_limits<int>::max());
      p.sightings = static_cast<int>(r.i64In("provisional sightings", 1, most));
    }
    if (scored_state) p.score = r.f64("provisional score");
    // Provisional while its score is below the confirming threshold (associate() erases it there).
    if (!std::isfinite(p.score) || (options.confirm_rule == ConfirmRule::Score && p.score >= trackConfirmScore())) {
      r.fail("provisional landmark " + std::to_string(id) + "'s track score is not finite or already confirms it");
    }
    p.held = r.u64Max("provisional held", 1) == 1;
    r.fixed("provisional mean", p.mean, true);
    r.fixed("provisional covariance", p.covariance, true);
    r.fixed("provisional lever", p.lever, true);
    s.provisional[id] = p;
  }
  s.touched = readIds(r, "touched landmarks");
  s.started = readIds(r, "started landmarks");
  s.refresh_cursor = static_cast<std::size_t>(r.u64("refresh cursor"));
  s.scans = static_cast<std::size_t>(r.u64("scans"));
  if (version >= 3) {
    s.footprint = SensorFootprint::restore(r);
  } else if (version == 2) {
    Vec2 lo, hi;
    r.fixed("footprint", lo);
    r.fixed("footprint", hi);
    // Empty (lo +inf, hi -inf) or a box of finite corners.
    const bool empty = (lo.array() == std::numeric_limits<double>::infinity()).all() &&
                       (hi.array() == -std::numeric_limits<double>::infinity()).all();
    if (!empty && !(lo.allFinite() && hi.allFinite() && (lo.array() <= hi.array()).all())) {
      r.fail("the sensor's footprint is neither empty nor a box");
    }
    s.footprint = SensorFootprint::fromBox(lo, hi);
  }
  if (scored_state) s.explained = static_cast<std::size_t>(r.u64Max("explained observations", s.counts.observations));
  for (const auto& [id, p] : s.provisional) {
    if (p.born > s.scans) r.fail("provisional landmark " + std::to_string(id) + " was started after the last scan");
  }
  r.finish();
  return std::move(*restored);
}

}  // namespace seif
