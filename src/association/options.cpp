// The table of association options (include/seif/association/association.hpp): each option's
// flag, attribute, kind, range and help, and how its value reads and prints as text.
// AssociationOptions documents what each one does; the help is the one line a flag shows.
#include <seif/association/association.hpp>

#include "filters/option_values.hpp"

#include <array>
#include <limits>

namespace seif {

namespace {

using Opt = AssociationOption;
using options::formatReal;
using options::parseIntegerOf;
using options::parseReal;
constexpr auto kChoice = Opt::Kind::Choice;
constexpr auto kInteger = Opt::Kind::Integer;
constexpr auto kProbability = Opt::Kind::Probability;
constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();

double probability(std::string_view key, std::string_view v) { return parseReal(key, v, 0.0, 1.0, true); }

const std::array<AssociationOption, 15> kOptions = {{
    {"association", "method", kChoice, "known|nn|jcbb", 0, 0, false,
     "data association: known (the dataset's landmark ids), nn (nearest neighbour: each observation its "
     "closest landmark inside the accept gate, greedily) or jcbb (joint compatibility branch and bound). "
     "With nn and jcbb the dataset's ids are hidden from the filter and only score the association "
     "(metrics.json \"association\"); docs/association.md",
     [](AssociationOptions& o, std::string_view v) { o.method = parseAssociationMethod(v); },
     [](const AssociationOptions& o) { return std::string(associationMethodName(o.method)); }},
    {"gate-marginal", "marginal", kChoice, "auto|exact|local|conservative", 0, 0, false,
     "the covariance the gates use: exact (the marginal), local (H inverted over a blanket around the "
     "pose and the candidates, at most seif:blanket variables more: constant time in the SEIF, smaller "
     "than the marginal), conservative (an upper bound, constant time in the SEIF with seif:bounds=true) "
     "or auto (local in the SEIF, exact in the others)",
     [](AssociationOptions& o, std::string_view v) { o.marginal = parseGateMarginal(v); },
     [](const AssociationOptions& o) { return std::string(gateMarginalName(o.marginal)); }},
    {"accept-gate", "accept", kProbability, "", 0, 0, true,
     "chi-square probability (2 dof) inside which an observation may be a landmark",
     [](AssociationOptions& o, std::string_view v) { o.accept = probability("accept-gate", v); },
     [](const AssociationOptions& o) { return formatReal(o.accept); }},
    {"new-gate", "new_landmark", kProbability, "", 0, 0, true,
     "chi-square probability beyond which an observation starts a new landmark (between the two gates "
     "it is dropped as ambiguous); >= --accept-gate",
     [](AssociationOptions& o, std::string_view v) { o.new_landmark = probability("new-gate", v); },
     [](const AssociationOptions& o) { return formatReal(o.new_landmark); }},
    {"confirm", "confirm", kInteger, "", 1, kIntMax, true,
     "a new landmark is provisional until seen this many times within --window scans; otherwise it is "
     "removed (1: keep every new landmark)",
     [](AssociationOptions& o, std::string_view v) { o.confirm = static_cast<int>(parseIntegerOf(kOptions, "confirm", v)); },
     [](const AssociationOptions& o) { return std::to_string(o.confirm); }},
    {"window", "window", kInteger, "", 0, kIntMax, true,
     "scans (steps with observations) a provisional landmark has to be confirmed in",
     [](AssociationOptions& o, std::string_view v) { o.window = static_cast<int>(parseIntegerOf(kOptions, "window", v)); },
     [](const AssociationOptions& o) { return std::to_string(o.window); }},
    {"confirm-rule", "confirm_rule", kChoice, "count|score", 0, 0, true,
     "how a provisional landmark is confirmed: count (--confirm sightings within --window scans) or score (a "
     "track score: each sighting weighed against the clutter density, each scan it lay in the sensor's "
     "footprint unseen against --detection-probability; undecided after --window scans, removed)",
     [](AssociationOptions& o, std::string_view v) { o.confirm_rule = parseConfirmRule(v); },
     [](const AssociationOptions& o) { return std::string(confirmRuleName(o.confirm_rule)); }},
    {"detection-probability", "detection_probability", kProbability, "", 0, 0, true,
     "with --confirm-rule score: the probability that a landmark in the sensor's footprint is reported",
     [](AssociationOptions& o, std::string_view v) {
       o.detection_probability = options::parseBetween("detection-probability", v, 0.0, 1.0);
     },
     [](const AssociationOptions& o) { return formatReal(o.detection_probability); }},
    {"clutter-density", "clutter_density", Opt::Kind::Real, "", 0, 0, true,
     "with --confirm-rule score: false detections per unit of measurement space (per m rad for range-bearing; "
     "0: estimated from the scans as the observations no confirmed landmark explained, per scan, over the footprint)",
     [](AssociationOptions& o, std::string_view v) {
       o.clutter_density = parseReal("clutter-density", v, 0.0, 1e100, false);
     },
     [](const AssociationOptions& o) { return formatReal(o.clutter_density); }},
    {"provisional", "provisional", kChoice, "filter|held", 0, 0, true,
     "where a provisional landmark lives: filter (in the filter from its first sighting, removed exactly if "
     "not confirmed) or held (outside it, its own small estimate, entering the filter at its confirming "
     "sighting: clutter never enters the filter)",
     [](AssociationOptions& o, std::string_view v) { o.provisional = parseProvisionalPlace(v); },
     [](const AssociationOptions& o) { return std::string(provisionalPlaceName(o.provisional)); }},
    {"merge", "merge", kProbability, "", 0, 0, true,
     "chi-square probability of the correspondence test that merges a landmark just seen into an older one "
     "nearby (0: never merge)",
     [](AssociationOptions& o, std::string_view v) { o.merge = probability("merge", v); },
     [](const AssociationOptions& o) { return formatReal(o.merge); }},
    {"jcbb-nodes", "jcbb_nodes", kInteger, "", 1, std::numeric_limits<std::int64_t>::max(), true,
     "most JCBB search nodes per scan; beyond, the best hypothesis found so far is used",
     [](AssociationOptions& o, std::string_view v) {
       o.jcbb_nodes = static_cast<std::size_t>(parseIntegerOf(kOptions, "jcbb-nodes", v));
     },
     [](const AssociationOptions& o) { return std::to_string(o.jcbb_nodes); }},
    {"refresh", "refresh", kInteger, "", 0, kIntMax, true,
     "landmarks re-indexed per scan besides the observed ones (cyclically), so that the grid follows means "
     "that move",
     [](AssociationOptions& o, std::string_view v) { o.refresh = static_cast<int>(parseIntegerOf(kOptions, "refresh", v)); },
     [](const AssociationOptions& o) { return std::to_string(o.refresh); }},
    {"slack", "slack", Opt::Kind::Length, "", 0, 0, true,
     "how far beyond the gate's reach (the point's and each landmark's own) the grid is queried, for means that "
     "moved more than their covariance claimed since indexed [m] (0: the new-landmark gate's radius at the "
     "first scan)",
     [](AssociationOptions& o, std::string_view v) { o.slack = options::parseLength("slack", v); },
     [](const AssociationOptions& o) { return formatReal(o.slack); }},
    {"drop-unlabelled", "drop_unlabelled", Opt::Kind::Flag, "", 0, 0, true,
     "with --association known: drop the observations without a landmark id (a simulated world's clutter) "
     "instead of refusing them; metrics.json counts them (association.unlabelled_dropped)",
     [](AssociationOptions& o, std::string_view v) { o.drop_unlabelled = options::parseBool("drop-unlabelled", v); },
     [](const AssociationOptions& o) { return std::string(o.drop_unlabelled ? "true" : "false"); }},
}};

}  // namespace

std::span<const AssociationOption> associationOptions() { return kOptions; }

void checkAssociationOptions(const AssociationOptions& values) {
  options::checkValues("association", kOptions, values, [](const AssociationOption&) { return true; });
}

}  // namespace seif
