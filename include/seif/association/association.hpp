#pragma once
// Data association: which mapped landmark each observation is of, when the sensor does not
// say (IJRR 2004 §4; Probabilistic Robotics §12.7; Neira & Tardos 2001). The run loop calls
// an Associator between predict and update (RunLoopOptions::associate): it gives every
// observation a landmark id - a mapped one, a new one, or none (dropped) - and keeps the
// map's provisional landmarks. Strategies: known (the data's ids), nn (individual
// compatibility, greedy by Mahalanobis distance), jcbb (joint compatibility branch and
// bound). Candidates come from a grid of landmark means queried around each observation,
// never from a scan of the map. docs/association.md has the rules and their defaults.
#include <seif/filters/slam_filter.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace seif {

enum class AssociationMethod {
  Known,             ///< the data's landmark ids (today's runs)
  NearestNeighbour,  ///< "nn": each observation its nearest compatible landmark, greedily
  Jcbb,              ///< "jcbb": the largest jointly compatible set of pairings
};

/// "known" | "nn" | "jcbb". Throws InvalidArgument naming the valid names.
AssociationMethod parseAssociationMethod(std::string_view s);
std::string_view associationMethodName(AssociationMethod m);

/// Where a provisional (not yet confirmed) landmark lives.
enum class ProvisionalPlace {
  /// "filter": in the filter from its first sighting, every sighting applied, removed
  /// exactly (SlamFilter::removeLandmark) when it is not confirmed in time.
  Filter,
  /// "held": outside the filter, as a small estimate of its own (a mean and a 2x2
  /// covariance, updated by each sighting with the pose's uncertainty taken as noise, no
  /// correlation kept); it enters the filter at its confirming sighting, initialised from
  /// that one (the earlier sightings are not applied). Clutter then never enters H: in the
  /// SEIF it never joins the active set nor pushes a tree out of it.
  Held,
};

/// "filter" | "held". Throws InvalidArgument naming the valid names.
ProvisionalPlace parseProvisionalPlace(std::string_view s);
std::string_view provisionalPlaceName(ProvisionalPlace p);

/// How a provisional landmark is confirmed (docs/association.md, "Provisional landmarks").
enum class ConfirmRule {
  /// "count": seen `confirm` times within `window` scans of its first sighting.
  Count,
  /// "score": a track score, Wald's sequential probability ratio test of "a landmark"
  /// against "clutter" (Blackman & Popoli 1999, §6.2). From 0 at its first sighting, each
  /// later sighting adds log(P_D N(nu; 0, S) / lambda) and each scan in which its predicted
  /// measurement lay in the sensor's footprint unseen adds log(1 - P_D). Confirmed at
  /// log((1 - beta) / alpha), removed at log(beta / (1 - alpha)) (alpha = kTrackFalseConfirm,
  /// beta = kTrackFalseDelete) or when `window` scans pass undecided. It weighs sightings
  /// against the clutter density, so clutter that a count would confirm is not.
  Score,
};

/// "count" | "score". Throws InvalidArgument naming the valid names.
ConfirmRule parseConfirmRule(std::string_view s);
std::string_view confirmRuleName(ConfirmRule r);

/// The track score's error probabilities (ConfirmRule::Score): alpha, of confirming clutter,
/// and beta, of removing a landmark.
inline constexpr double kTrackFalseConfirm = 1e-3;
inline constexpr double kTrackFalseDelete = 1e-2;

struct AssociationOptions {
  AssociationMethod method = AssociationMethod::Known;
  /// Chi-square probability of the accept gate (2 dof): an observation whose Mahalanobis
  /// distance to a landmark is inside it may be that landmark.
  double accept = 0.99;
  /// Chi-square probability of the new-landmark gate: an observation farther than it from
  /// every landmark starts a new one; between the gates it is dropped as ambiguous.
  double new_landmark = 0.9999;
  /// The covariance the gates use (SlamFilter::marginal): Exact, Local (constant time in
  /// the SEIF, its blanket bounded by SeifOptions::blanket; conditions on the blanket's
  /// outside, so it is never larger than the marginal) or Conservative (an upper bound: the
  /// SEIF needs SeifOptions::bounds, see needsCovarianceBounds()). Unset ("auto"): the
  /// filter's SlamFilter::gateMarginal(), Local in the SEIF and Exact in the others.
  std::optional<MarginalMode> marginal;
  /// A new landmark stays provisional until it has been seen `confirm` times (its first
  /// sighting included) within `window` scans (steps with observations) of its first;
  /// otherwise it is removed (from the filter exactly, or dropped when held: `provisional`).
  /// confirm = 1 keeps every new landmark. Chosen on the park with one false detection per
  /// scan (docs/association.md).
  int confirm = 4;
  int window = 20;
  /// Count (`confirm` sightings in `window` scans) or Score (a track score weighing each
  /// sighting against the clutter density and each miss against `detection_probability`;
  /// `confirm` unused, `window` the longest it stays undecided).
  ConfirmRule confirm_rule = ConfirmRule::Count;
  /// Score: the probability P_D that a landmark in the sensor's footprint is reported. The
  /// footprint is where, in measurement space (range and bearing), the observations so far
  /// lie: per axis, the intervals they cover, joined across gaps under ten standard
  /// deviations of the sensor's noise (an outlying range adds no length; a bearing wraps).
  double detection_probability = 0.9;
  /// Score: false detections per unit of measurement space (per m rad for range-bearing).
  /// 0: estimated from the scans so far, as the observations no confirmed landmark explained
  /// (new landmarks started, ambiguous ones dropped, sightings of provisional ones) per scan
  /// over the footprint's volume - an upper bound, since a landmark's sightings before it is
  /// confirmed count as clutter there.
  double clutter_density = 0.0;
  ProvisionalPlace provisional = ProvisionalPlace::Filter;
  /// Known: drop the observations the data names no landmark for (clutter in a simulated
  /// world) and count them, instead of refusing the step - the reference run that knows
  /// the association of a cluttered world.
  bool drop_unlabelled = false;
  /// Chi-square probability (2 dof) of the correspondence test: a landmark observed in the
  /// last scan is merged into an older one nearby (not seen in the same scan) when their
  /// difference is inside it (SlamFilter::mergeLandmarks). 0: never merge.
  double merge = 0.95;
  /// jcbb: most search nodes per scan; when reached, the best hypothesis found so far is
  /// used and the scan is counted in AssociationCounts::jcbb_truncated.
  std::size_t jcbb_nodes = 20000;
  /// The grid of landmark means: the observed landmarks and `refresh` others (in map order,
  /// cyclically) are re-indexed every step, and queries reach `slack` [m] beyond the
  /// gate's radius for means that moved since they were indexed.
  int refresh = 16;
  double slack = 0.0;  ///< 0: the radius of the new-landmark gate at the first scan
};

/// Whether these options gate with conservative marginals, which a SEIF answers only with
/// its covariance bounds kept (SeifOptions::bounds): `seif run` and `seif bench` turn them on.
bool needsCovarianceBounds(const AssociationOptions& o);

/// AssociationOptions::marginal as text: "auto" when unset, else marginalModeName(); and back
/// (InvalidArgument naming the valid names).
std::string_view gateMarginalName(std::optional<MarginalMode> m);
std::optional<MarginalMode> parseGateMarginal(std::string_view s);

/// One option of data association. The table of them (associationOptions()) is the single
/// description the CLI's flags (`--<key>`), metrics.json's "association" object and Python's
/// table (seif.association_options()) come from; `attribute` names the AssociationOptions
/// member (Python's attribute, the json key).
struct AssociationOption {
  /// Probability: a probability, in [0, 1) (detection-probability: in (0, 1)). Real: a
  /// non-negative number. Flag: true | false (a bare flag).
  enum class Kind { Choice, Integer, Probability, Length, Real, Flag };
  std::string_view key;        ///< the flag, "accept-gate"
  std::string_view attribute;  ///< "accept"
  Kind kind;
  std::string_view choices;  ///< Choice: the values, "known|nn|jcbb"
  std::int64_t min = 0;      ///< Integer: the range
  std::int64_t max = 0;
  bool tuning = true;  ///< false: a flag of every command that associates (`run` and `bench`)
  std::string_view help;
  /// Sets the option from its text; throws InvalidArgument naming key and value.
  void (*set)(AssociationOptions& options, std::string_view value);
  /// The option's value, as text set() takes.
  std::string (*get)(const AssociationOptions& options);
};

/// Every association option, in the order metrics.json lists them.
std::span<const AssociationOption> associationOptions();

/// What the association did, scored at finish() against Observation::truth where the data
/// names one. Each landmark is labelled with the truth id most of its observations carry
/// (an older landmark keeps a label two share); an observation with a truth id in a
/// landmark at the end is correct when the landmark's label is its truth and the landmark
/// is not a duplicate.
struct AssociationCounts {
  std::size_t observations = 0;       ///< observations the associator saw
  std::size_t scored = 0;             ///< with a truth id, in a landmark at the end
  std::size_t correct = 0;            ///< of them, in the landmark labelled with their truth
  std::size_t wrong = 0;              ///< of them, not
  std::size_t unlabelled = 0;         ///< without a truth id (clutter, an unmatched detection), in a landmark
  std::size_t unlabelled_matched = 0;  ///< of them, in a landmark labelled with a truth id
  std::size_t in_removed_landmarks = 0;  ///< in provisional landmarks removed
  std::size_t new_landmarks = 0;      ///< landmarks started
  std::size_t ambiguous_dropped = 0;  ///< between the gates: dropped
  std::size_t unlabelled_dropped = 0;  ///< known, drop_unlabelled: without a landmark id, dropped
  std::size_t provisional_removed = 0;  ///< provisional landmarks not confirmed in time
  std::size_t provisional_final = 0;    ///< still provisional at the end, kept in the map (a smoother, a stop)
  std::size_t merged = 0;             ///< landmarks merged into another
  std::size_t jcbb_truncated = 0;     ///< scans whose search reached jcbb_nodes
  std::size_t landmarks_final = 0;    ///< landmarks in the map at finish()
  std::size_t spurious_landmarks = 0;   ///< of them, with no observation that has a truth id
  std::size_t duplicate_landmarks = 0;  ///< of them, with the label of an older one
  double seconds = 0.0;               ///< wall time spent associating
};

/// What associate() decided for one observation of its scan (Associator::lastScan()).
struct ScanDecision {
  enum class Outcome {
    Matched,    ///< paired with a mapped or provisional landmark inside the accept gate
    New,        ///< beyond the new-landmark gate of every landmark: a new landmark started
    Ambiguous,  ///< neither: dropped
  };
  Outcome outcome = Outcome::Ambiguous;
  int landmark = kUnknownLandmark;  ///< Matched, New: the landmark; Ambiguous: kUnknownLandmark
  /// The landmark is still provisional after this sighting (not confirmed yet).
  bool provisional = false;
  /// The observation is among those associate() left for the filter's update: not when
  /// dropped, nor when it is a sighting of a held provisional landmark (ProvisionalPlace::Held).
  bool applied = false;
  /// Matched: the pairing's squared Mahalanobis distance. New, Ambiguous: that to the nearest
  /// landmark in reach (infinity when none was).
  double d2 = 0.0;
};

std::string_view scanOutcomeName(ScanDecision::Outcome o);  ///< "matched" | "new" | "ambiguous"

/// Two landmarks the correspondence test found to be one (Associator::lastMerges()):
/// `merged` went into `kept` (SlamFilter::mergeLandmarks), its observations with it.
struct LandmarkMerge {
  int kept = kUnknownLandmark;
  int merged = kUnknownLandmark;
};

/// The correspondence test (IJRR 2004 §4; Probabilistic Robotics §12.7): the squared
/// Mahalanobis distance of Delta = y_a - y_b, Sigma_Delta = F_Delta Sigma F_Delta^T over the
/// joint marginal of landmarks a and b (SlamFilter::marginal with `mode`). Small: they may be
/// one landmark (SlamFilter::mergeLandmarks). Infinity when Sigma_Delta is singular.
double correspondenceDistance(const SlamFilter& filter, int a, int b, MarginalMode mode = MarginalMode::Exact);

/// The key of a run checkpoint's extras that holds its associator (Associator::saveState).
inline constexpr std::string_view kAssociatorKey = "associator";

class Associator {
 public:
  explicit Associator(const AssociationOptions& options);
  ~Associator();
  Associator(Associator&&) noexcept;
  Associator& operator=(Associator&&) noexcept;

  /// Gives each of `observations` (made at step k, after the filter's predict) a landmark
  /// id, or removes it (dropped as ambiguous); removes the provisional landmarks whose
  /// window has passed. Known: checks every observation has an id and changes nothing.
  void associate(SlamFilter& filter, std::size_t k, std::vector<Observation>& observations);
  /// The filter refused the update of the last associate()'s observations, and the caller
  /// goes on: forgets what they counted - their sightings of provisional landmarks (none is
  /// confirmed by them), the landmarks they started (their ids are given again), the truth
  /// tallies and counts - as if the scan had been empty. What that associate() did to the
  /// filter itself (expiries, merges) stays. Does nothing once the next associate() or
  /// finish() has run. (The run loop stops at a refused update instead.)
  void discardScan();
  /// After the run: removes the landmarks still provisional (not from a smoother) and
  /// scores the association (landmarks_final, correct, spurious, duplicates, ...). Once
  /// `stop` is set the removals stop: the landmarks left keep their place in the map and are
  /// counted in provisional_final, as a smoother's are (runFilter passes its stop: a run
  /// stopped then is interrupted, and its checkpoint finishes the removals).
  void finish(SlamFilter& filter, const std::atomic<bool>* stop = nullptr);

  const AssociationCounts& counts() const;
  /// What the last associate() decided, one entry per observation it was given, in their
  /// order: what became of the ones it dropped, and how far each was from its landmark.
  /// Empty with known association, after a step without observations, and in an associator
  /// just restored (it is not part of saveState()).
  std::span<const ScanDecision> lastScan() const;
  /// The merges the last associate() made before associating its scan, in the order made
  /// (a landmark merged may have been kept by an earlier one). Empty as lastScan() is.
  std::span<const LandmarkMerge> lastMerges() const;
  /// Landmark `id`'s label: the truth id most of its observations carried (kUnknownLandmark
  /// when none had one): to score a map against ground truth.
  int truthOf(int id) const;
  /// Whether landmark `id` shares its label with an older landmark (a smaller id) of the map
  /// finish() scored: a duplicate, whose observations it counted wrong. False before finish().
  bool isDuplicate(int id) const;
  const AssociationOptions& options() const;

  /// The associator's whole state - options, counts, index, provisional landmarks, the
  /// tallies that score it - as checkpoint bytes (a run's checkpoint carries them beside the
  /// filter, under kAssociatorKey): restoreState() continues it bit for bit.
  std::string saveState() const;
  /// The associator saveState() wrote. Throws DataError naming `name` for anything else.
  static Associator restoreState(std::string_view bytes, const std::string& name);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace seif
