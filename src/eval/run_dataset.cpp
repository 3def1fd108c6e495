// `seif run` as one library call (include/seif/eval/run_dataset.hpp).
#include <seif/core/errors.hpp>
#include <seif/core/version.hpp>
#include <seif/eval/bench.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/filters/checkpoint.hpp>
#include <seif/filters/factory.hpp>
#include <seif/models/velocity_model.hpp>
#include "core/binary_archive.hpp"
#include "core/files.hpp"
#include "filters/option_values.hpp"
#include <seif/io/results.hpp>

#include "json_fields.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

namespace seif {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// `filter` (a spec) with the request's flags as the defaults of the options it does not set.
FilterSpec flaggedSpec(const RunRequest& request, std::string_view filter) {
  FilterSpec defaults;
  defaults.linearization = request.linearization;
  defaults.iterations = request.iterations;
  defaults.seif = request.seif;
  defaults.batch = request.batch;
  return parseFilterSpec(filter, defaults);
}

/// flaggedSpec(), with the covariance bounds the association's gate needs.
FilterSpec requestedSpec(const RunRequest& request, std::string_view filter) {
  FilterSpec spec = flaggedSpec(request, filter);
  if (needsCovarianceBounds(request.association)) spec.seif.bounds = true;
  return spec;
}

nlohmann::json optionalJson(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

// `run_correct_fraction`: the run's correct associations over the same labelled observations
// (its own correct_fraction is over those it kept, which dropping ambiguous ones raises).
nlohmann::json ceilingJson(const std::optional<AssociationCeiling>& c, const AssociationCounts& run) {
  if (!c) return nullptr;
  auto fraction = [&](std::size_t n) {
    return c->observations == 0 ? nlohmann::json(nullptr) : nlohmann::json(double(n) / double(c->observations));
  };
  return {{"observations", c->observations},
          {"individual", c->individual},
          {"individual_fraction", fraction(c->individual)},
          {"joint", c->joint},
          {"joint_fraction", fraction(c->joint)},
          {"run_correct_fraction", fraction(run.correct)},
          {"scans", c->scans},
          {"joint_truncated", c->joint_truncated},
          {"definition", "the labelled observations associated with the true landmarks seen from the true pose: "
                         "each to its most likely landmark (individual), or by the scan's most likely one-to-one "
                         "assignment (joint); what a perfect map and pose would get"}};
}

/// The message of a run's failure (RunOutput::failure).
std::string failureMessage(const std::exception_ptr& failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "an unknown error";
  }
}

/// Removes what an earlier run wrote into `out`, so that none of it outlives this run as if
/// it were this run's (a failed run writes only what it ran; an option left out writes less).
void removeEarlierOutputs(const std::filesystem::path& out) {
  for (const char* name : {"trajectory.tum", "dead_reckoning.tum", "map.csv", "metrics.json", "gps.csv",
                           "trajectory_filter.tum", "map_filter.csv", "trajectory_cov.csv", "associations.csv", "groundtruth.tum",
                           "landmarks_groundtruth.csv", "map.png"}) {
    std::filesystem::remove(out / name);
  }
}

std::string metricsJson(const RunRequest& request, const RunReport& r) {
  const RunOutput& out = r.output;
  std::vector<double> sorted = out.step_seconds;
  std::sort(sorted.begin(), sorted.end());
  nlohmann::json noise = nlohmann::json::array();
  for (const NoiseSetting& n : r.info.noise) {
    noise.push_back({{"name", n.name}, {"value", n.value ? nlohmann::json(*n.value) : nlohmann::json()}, {"unit", n.unit},
                     {"source", n.source}});
  }
  nlohmann::json dropped = nlohmann::json::object();
  for (const auto& [reason, count] : out.dropped) dropped[reason] = count;
  const double steps = static_cast<double>(out.steps);
  nlohmann::json j = {
      {"version", kVersion},
      {"command_line", request.command_line},
      {"dataset", request.dataset.string()},
      {"format", r.info.format},
      {"filter", r.filter},
      {"motion_model", r.info.motion->describe()},
      {"sensor_model", r.info.sensor->describe()},
      {"noise", noise},
      {"start_pose", {r.info.start_pose.x(), r.info.start_pose.y(), r.info.start_pose.z()}},
      {"start_pose_source", r.info.start_pose_source},
      {"steps", out.steps},
      {"interrupted", out.interrupted},
      {"failure", out.failure ? nlohmann::json(failureMessage(out.failure)) : nlohmann::json(nullptr)},
      {"landmarks", r.landmarks},
      {"seconds", out.seconds},
      {"seconds_wall", r.seconds_wall},
      {"seconds_trajectory_and_map", r.seconds_outputs},
      {"map_covariances", request.map_covariances},
      {"trajectory_covariances", request.trajectory_covariances},
      {"us_per_step", out.steps == 0 ? 0.0 : 1e6 * out.seconds / steps},
      {"us_per_step_median", sorted.empty() ? 0.0 : 1e6 * sorted[sorted.size() / 2]},
      {"links", out.final_stats.links},
      {"robot_links", out.final_stats.robot_links},
      {"max_robot_links", out.max_robot_links},
      {"max_landmark_links", out.final_stats.max_landmark_links},
      {"information_scale", out.final_stats.information_scale},
      {"max_blocks_touched", out.max_blocks_touched},
      {"rejected_observations", out.rejected_observations},
      {"outlier_gate_sigmas", std::isinf(request.outlier_gate) ? nlohmann::json(nullptr) : nlohmann::json(request.outlier_gate)},
      {"landmark_rmse", optionalJson(r.errors.landmark)},
      {"ate_rmse", optionalJson(r.errors.ate)},
      {"dead_reckoning_ate_rmse", optionalJson(r.errors.dead_reckoning_ate)},
      {"landmark_rmse_unaligned", optionalJson(r.errors.landmark_unaligned)},
      {"ate_rmse_unaligned", optionalJson(r.errors.ate_unaligned)},
      {"dead_reckoning_ate_rmse_unaligned", optionalJson(r.errors.dead_reckoning_ate_unaligned)},
      {"gps_rmse", optionalJson(r.errors.gps)},
      {"dead_reckoning_gps_rmse", optionalJson(r.errors.dead_reckoning_gps)},
      {"gps_fixes", r.errors.gps_fixes},
      {"gps_median_error", optionalJson(r.errors.gps_median)},
      {"gps_rmse_without_jumps", optionalJson(r.errors.gps_without_jumps)},
      {"gps_jumps", r.errors.gps_jumps},
      {"errors", "*_rmse: after the best rigid 2-D alignment to the reference (ground truth or GPS, "
                 "at its stamps); *_unaligned: as estimated, in the ground truth's frame"},
      {"dropped", dropped},
  };
  if (request.format == DatasetFormat::Mrclam || r.info.format == "mrclam") j["robot"] = request.dataset_options.robot;
  if (request.smooth) j["smooth"] = true;
  if (r.association) {
    const AssociationCounts& a = *r.association;
    const AssociationOptions& o = r.association_options;
    j["association"] = toJson(o);  // the options, then what they did
    j["association"].update(nlohmann::json{
        {"observations", a.observations},
        {"scored", a.scored},
        {"correct", a.correct},
        {"wrong", a.wrong},
        {"correct_fraction", a.scored == 0 ? nlohmann::json(nullptr) : nlohmann::json(double(a.correct) / double(a.scored))},
        {"unlabelled", a.unlabelled},
        {"unlabelled_matched", a.unlabelled_matched},
        {"in_removed_landmarks", a.in_removed_landmarks},
        {"new_landmarks", a.new_landmarks},
        {"spurious_landmarks", a.spurious_landmarks},
        {"duplicate_landmarks", a.duplicate_landmarks},
        {"ambiguous_dropped", a.ambiguous_dropped},
        {"unlabelled_dropped", a.unlabelled_dropped},
        {"provisional_removed", a.provisional_removed},
        {"provisional_final", a.provisional_final},
        {"merged", a.merged},
        {"jcbb_truncated", a.jcbb_truncated},
        {"landmarks_final", a.landmarks_final},
        {"seconds", a.seconds},
        {"ceiling", ceilingJson(r.association_ceiling, a)},
        {"scoring", "each landmark is labelled with the truth id most of its observations carry (the older of "
                    "two with one label keeps it); scored: observations with a truth id in a landmark at the end; "
                    "correct: in the landmark labelled with their truth"}});
  }
  if (r.smoother) {
    const SmootherReport& b = *r.smoother;
    j["batch"] = {{"init", b.init},
                  {"poses", b.poses},
                  {"landmarks", b.landmarks},
                  {"constraints", b.constraints},
                  {"iterations", b.iterations},
                  {"converged", b.converged},
                  {"initial_cost", b.initial_cost},
                  {"final_cost", b.final_cost},
                  {"gradient_norm", b.gradient_norm},
                  {"initial_gradient_norm", b.initial_gradient_norm},
                  {"solve_seconds", b.solve_seconds},
                  {"linearize_seconds", b.linearize_seconds},
                  {"factorize_seconds", b.factorize_seconds},
                  {"step_seconds", b.step_seconds},
                  {"factor_nonzeros", b.factor_nonzeros},
                  {"costs", b.costs},
                  {"cost", "0.5 chi-square: the sum of squared whitened residuals over two"}};
  }
  if (r.filter_errors) {
    const RunErrors& f = *r.filter_errors;
    j["filter_before_smoothing"] = {{"landmark_rmse", optionalJson(f.landmark)},
                                    {"ate_rmse", optionalJson(f.ate)},
                                    {"gps_rmse", optionalJson(f.gps)},
                                    {"gps_median_error", optionalJson(f.gps_median)},
                                    {"gps_rmse_without_jumps", optionalJson(f.gps_without_jumps)},
                                    {"map_distance_to_batch", optionalJson(r.filter_map_distance)}};
    if (r.filter_trajectory_distance) {
      j["filter_before_smoothing"]["trajectory_distance_to_batch"] = {
          {"rms", (*r.filter_trajectory_distance)(0)},
          {"median", (*r.filter_trajectory_distance)(1)},
          {"definition", "distance of the filter's position from the batch's at every pose [m]"}};
    }
    if (r.filter_covariance_ratio) {
      const Vec3& c = *r.filter_covariance_ratio;
      j["filter_before_smoothing"]["landmark_covariance_ratio_to_batch"] = {
          {"median", c(0)}, {"p10", c(1)}, {"p90", c(2)},
          {"definition", "over the landmarks, trace(filter's covariance) / trace(batch's): 1 honest, below 1 overconfident"}};
    }
  }
  // The configuration the filter ran with, written as a spec that parses back to it.
  const FilterSpec spec = requestedSpec(request, r.filter);
  j["filter_spec"] = canonicalFilterSpec(spec);
  if (spec.name == "seif") j["seif"] = toJson(spec.seif);
  return j.dump(2) + "\n";
}

}  // namespace

std::string seifOptionsJson(const SeifOptions& o) { return toJson(o).dump(); }

std::optional<double> gpsRmse(const std::vector<TimedPose>& trajectory, const std::vector<GpsFix>& gps,
                              std::size_t* compared, std::optional<double>* median) {
  if (compared) *compared = 0;
  if (trajectory.empty()) return std::nullopt;
  const double t0 = trajectory.front().time, t1 = trajectory.back().time;
  std::vector<Vec2> est, ref;
  for (const GpsFix& g : gps) {
    if (g.time < t0 || g.time > t1) continue;
    est.push_back(interpolatePose(trajectory, g.time).head<2>());
    ref.push_back(g.position);
  }
  if (compared) *compared = est.size();
  if (est.size() < 2) return std::nullopt;
  std::vector<double> residuals;
  const double rmse = alignedRmse(est, ref, Alignment::Rigid, &residuals);
  if (median) {
    std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
    *median = residuals[residuals.size() / 2];
  }
  return rmse;
}

std::vector<bool> gpsJumps(const std::vector<GpsFix>& gps, double max_speed) {
  // The speed implied between fixes i and i + 1; a repeated stamp with a moved fix is infinite.
  auto tooFast = [&](std::size_t i) {
    const double dt = gps[i + 1].time - gps[i].time;
    return (gps[i + 1].position - gps[i].position).norm() > max_speed * dt;
  };
  std::vector<bool> jump(gps.size(), false);
  if (gps.size() < 2) return jump;
  for (std::size_t i = 0; i < gps.size(); ++i) {
    const bool before = i == 0 || tooFast(i - 1);
    const bool after = i + 1 == gps.size() || tooFast(i);
    jump[i] = before && after;
  }
  return jump;
}

RunErrors evaluateRun(const SlamFilter& filter, const DatasetInfo& info, const RunOutput& out) {
  RunErrors e;
  e.ate = ateRmse(out.trajectory, out.groundtruth, Alignment::Rigid);
  e.dead_reckoning_ate = ateRmse(out.dead_reckoning, out.groundtruth, Alignment::Rigid);
  e.landmark = landmarkRmse(filter, info.landmarks, Alignment::Rigid);
  e.ate_unaligned = ateRmse(out.trajectory, out.groundtruth);
  e.dead_reckoning_ate_unaligned = ateRmse(out.dead_reckoning, out.groundtruth);
  e.landmark_unaligned = landmarkRmse(filter, info.landmarks);
  e.gps = gpsRmse(out.trajectory, out.gps, &e.gps_fixes, &e.gps_median);
  e.dead_reckoning_gps = gpsRmse(out.dead_reckoning, out.gps);
  if (e.gps) {
    const std::vector<bool> jump = gpsJumps(out.gps);
    std::vector<GpsFix> kept;
    for (std::size_t i = 0; i < out.gps.size(); ++i) {
      if (!jump[i]) kept.push_back(out.gps[i]);
    }
    std::size_t compared = 0;
    e.gps_without_jumps = gpsRmse(out.trajectory, kept, &compared);
    e.gps_jumps = e.gps_fixes - compared;
  }
  return e;
}

namespace {

/// A checkpoint is written over `path` only where nothing is or a checkpoint was: never over
/// another file (a dataset's own, given by mistake). Throws InvalidArgument naming it.
void checkCheckpointTarget(const std::filesystem::path& path) {
  std::error_code ec;
  if (path.empty() || !std::filesystem::exists(path, ec)) return;
  std::string head(kArchiveMagic.size(), '\0');
  std::ifstream in(path, std::ios::binary);
  const bool checkpoint = std::filesystem::is_regular_file(path, ec) && in.read(head.data(), static_cast<std::streamsize>(head.size())) &&
                          head == kArchiveMagic;
  if (!checkpoint) {
    throw InvalidArgument("checkpoint: " + path.string() +
                          " exists and is not a seif checkpoint; refusing to write over it (give a new file)");
  }
}

/// What selects and shapes the events a dataset yields, as text a checkpoint records:
/// a resumed run must read the same events.
std::string datasetOptionsText(const std::string& format, const DatasetOptions& o) {
  std::ostringstream text;
  text << "format " << format << ", robot " << o.robot << ", detections "
       << detectionsName(o.detections) << ", noise form "
       << (o.noise_form ? std::string(noiseFormName(*o.noise_form)) : std::string("default"))
       << ", iSAM landmarks as GTSAM " << (o.isam_landmarks_as_gtsam ? "yes" : "no") << ", noise {";
  for (const auto& [key, value] : o.noise) text << ' ' << key << ' ' << options::formatReal(value);
  text << " }";
  return text.str();
}

/// Every association option as `--key value`, in the table's order.
std::string associationOptionsText(const AssociationOptions& o) {
  std::string text;
  for (const AssociationOption& option : associationOptions()) {
    text += (text.empty() ? "--" : " --") + std::string(option.key) + " " + option.get(o);
  }
  return text;
}

/// What a run's report and outputs add to its RunOutput: errors against each reference,
/// a smoother's figures, the association's ceiling; then the files written into `out`.
void finishReport(const RunRequest& request, const std::filesystem::path& out, const SlamFilter& filter,
                  const Associator& associator, Clock::time_point start, RunReport& report) {
  const bool associating = associator.options().method != AssociationMethod::Known;
  const std::exception_ptr failure = report.output.failure;
  report.seconds_wall = secondsSince(start);
  // An evaluation, not timed; it rereads the whole dataset, which a failed run did not get through.
  if (associating && !failure && report.info.has_groundtruth && !report.info.landmarks.empty()) {
    const auto reread = openDataset(request.dataset, request.format, request.dataset_options);
    report.association_ceiling = associationCeiling(*reread, *report.info.sensor);
  }
  report.landmarks = filter.landmarkIds().size();
  DatasetInfo scored_info = report.info;
  if (associating) {  // the associator's landmarks against the true landmark each was started from
    scored_info.landmarks.clear();
    for (int id : filter.landmarkIds()) {
      const auto it = report.info.landmarks.find(associator.truthOf(id));
      if (it != report.info.landmarks.end()) scored_info.landmarks[id] = it->second;
    }
  }
  report.errors = evaluateRun(filter, scored_info, report.output);
  if (const SmootherReport* b = filter.smootherReport()) report.smoother = *b;
  const SlamFilter* filtered = request.smooth ? smoothedFilter(filter) : nullptr;
  if (filtered) {
    RunOutput before = report.output;
    before.trajectory = report.output.filter_trajectory;
    report.filter_errors = evaluateRun(*filtered, scored_info, before);
    double sum = 0.0;
    for (int id : filter.landmarkIds()) sum += (filtered->landmark(id) - filter.landmark(id)).squaredNorm();
    if (!filter.landmarkIds().empty()) report.filter_map_distance = std::sqrt(sum / static_cast<double>(filter.landmarkIds().size()));
    const std::vector<TimedPose>& batch_poses = report.output.trajectory;
    const std::vector<TimedPose>& filter_poses = report.output.filter_trajectory;
    if (!batch_poses.empty() && batch_poses.size() == filter_poses.size()) {
      std::vector<double> d(batch_poses.size());
      double squares = 0.0;
      for (std::size_t k = 0; k < d.size(); ++k) {
        d[k] = (filter_poses[k].pose.head<2>() - batch_poses[k].pose.head<2>()).norm();
        squares += d[k] * d[k];
      }
      report.filter_trajectory_distance = Vec2(std::sqrt(squares / static_cast<double>(d.size())), quantile(d, 0.5));
    }
    std::vector<double> ratios;
    for (int id : filter.landmarkIds()) {
      const double batch = filter.landmarkCovariance(id).trace();
      if (batch > 0.0) ratios.push_back(filtered->landmarkCovariance(id).trace() / batch);
    }
    if (!ratios.empty()) {
      report.filter_covariance_ratio = Vec3(quantile(ratios, 0.5), quantile(ratios, 0.1), quantile(ratios, 0.9));
    }
  }

  const auto write_start = Clock::now();
  writeTum(out / "trajectory.tum", report.output.trajectory);
  writeTum(out / "dead_reckoning.tum", report.output.dead_reckoning);
  try {
    writeMapCsv(out / "map.csv", filter, request.map_covariances);  // marginals computed here
  } catch (const Error&) {
    // A failed run's filter may hold information no factorisation takes, or values that are
    // not finite: its map, then, without covariances and without those rows (the run's own
    // failure is reported). A run that had not failed fails here, its other outputs written.
    if (!failure) report.output.failure = std::current_exception();
    writeMapCsv(out / "map.csv", filter, false, NonFiniteRows::Omit);
  }
  if (filtered) {
    writeTum(out / "trajectory_filter.tum", report.output.filter_trajectory);
    writeMapCsv(out / "map_filter.csv", *filtered, request.map_covariances);
  }
  if (!report.output.gps.empty()) writeGpsCsv(out / "gps.csv", report.output.gps);  // for `seif plot`
  if (!report.output.groundtruth.empty()) writeTum(out / "groundtruth.tum", report.output.groundtruth);
  if (!report.info.landmarks.empty()) writeLandmarkTruthCsv(out / "landmarks_groundtruth.csv", report.info.landmarks);
  // Each observation's association; not after a resume from a checkpoint that kept none.
  if (associating && report.output.associations_from == 0) {
    writeAssociationsCsv(out / "associations.csv", report.output, filter, associator);
  }
  if (request.trajectory_covariances) {
    writeTrajectoryCovariance(out / "trajectory_cov.csv", report.output.trajectory, report.output.pose_covariances);
  }
  report.seconds_outputs = secondsSince(write_start);
  writeFileAtomically(out / "metrics.json", metricsJson(request, report));
}

}  // namespace

RunReport runDataset(const RunRequest& request, const std::filesystem::path& out,
                     const std::function<void(double)>& progress) {
  const auto start = Clock::now();
  std::unique_ptr<EventSource> source = openDataset(request.dataset, request.format, request.dataset_options);
  RunReport report;
  FilterConfig config;
  config.motion = source->info().motion;
  config.sensor = source->info().sensor;
  config.outlier_gate = request.outlier_gate;
  config.linearization = request.linearization;
  config.iterations = request.iterations;
  if (request.checkpoint_every > 0 && request.checkpoint.empty()) {
    throw InvalidArgument("checkpoints: checkpoint_every needs a checkpoint file");
  }
  // The raw detections carry no landmark id: known association would fail at the first one.
  if (request.dataset_options.detections == Detections::Raw && request.resume.empty() &&
      request.association.method == AssociationMethod::Known && !request.association.drop_unlabelled) {
    throw InvalidArgument("raw detections (dataset_options.detections, --detections raw) carry no landmark id: "
                          "associate them (association.method nn or jcbb, --association), or drop them with known "
                          "association (association.drop_unlabelled, --drop-unlabelled)");
  }
  checkCheckpointTarget(request.checkpoint);
  RunCheckpointing checkpointing;
  checkpointing.every = request.checkpoint_every;
  checkpointing.path = request.checkpoint;
  checkpointing.values = {{"dataset", std::filesystem::absolute(request.dataset).lexically_normal().string()},
                          {"dataset-options", datasetOptionsText(source->info().format, request.dataset_options)},
                          {"filter", request.filter},
                          {"filter-spec", canonicalFilterSpec(flaggedSpec(request, request.filter))}};
  std::unique_ptr<SlamFilter> filter;
  std::optional<RunResume> resume;
  if (!request.resume.empty()) {
    CheckpointExtras extras;
    filter = load(request.resume, &extras);
    const std::string name = request.resume.string();
    if (extras.values["dataset"] != checkpointing.values["dataset"]) {
      throw DataError(name, 0, "the checkpoint is of the run of " + extras.values["dataset"] + ", not of " +
                                   checkpointing.values["dataset"]);
    }
    // The same events: a checkpoint from before dataset options were recorded is taken as is.
    if (const auto o = extras.values.find("dataset-options");
        o != extras.values.end() && o->second != checkpointing.values["dataset-options"]) {
      throw DataError(name, 0, "the checkpoint's run read its dataset with " + o->second + ", this run with " +
                                   checkpointing.values["dataset-options"] + " (give the same options)");
    }
    // The filter is the checkpoint's: a spec or filter options given (the request is not the
    // defaults) that differ from its run's, or smoothing (which keeps every measurement and
    // so has no checkpoint), would be silently ignored. Compared as canonical specs; a
    // checkpoint from before they were recorded is compared by its spec's text.
    RunRequest unasked;
    const std::string asked = canonicalFilterSpec(flaggedSpec(request, request.filter));
    if (asked != canonicalFilterSpec(flaggedSpec(unasked, unasked.filter))) {
      const auto ran = extras.values.find("filter-spec");
      const std::string ran_spec = ran != extras.values.end() ? ran->second
                                                              : canonicalFilterSpec(parseFilterSpec(extras.values["filter"]));
      if (asked != ran_spec) {
        throw InvalidArgument("resume: the checkpoint's run is of " + ran_spec + "; this run asks for " + asked +
                              " (give it, or no filter or filter options: a resumed run continues the checkpoint's filter)");
      }
    }
    if (request.smooth) throw InvalidArgument("resume: a run resumed from a checkpoint cannot be smoothed (smooth, --smooth)");
    checkpointing.values["filter"] = extras.values["filter"];
    if (const auto ran = extras.values.find("filter-spec"); ran != extras.values.end()) {
      checkpointing.values["filter-spec"] = ran->second;
    } else {
      checkpointing.values.erase("filter-spec");
    }
    resume = runResumeFrom(extras.values, static_cast<std::size_t>(extras.steps_consumed), name);
  } else {
    const FilterSpec spec = requestedSpec(request, request.filter);
    if (!request.checkpoint.empty() && (request.smooth || spec.name == "batch")) {
      throw InvalidArgument("checkpoints: the batch MAP (and smooth, --smooth) keeps every measurement and has no checkpoint");
    }
    filter = request.smooth ? makeSmoother(spec, source->info().start_pose, config, request.batch)
                            : makeFilter(spec, source->info().start_pose, config);
  }
  // A resumed run continues the checkpoint's associator, as it continues its filter.
  Associator associator = resume && !resume->associator.empty()
                              ? Associator::restoreState(resume->associator, request.resume.string())
                              : Associator(request.association);
  // Association flags given (the request is not the defaults) must be the checkpoint's.
  if (resume) {
    const std::string asked = associationOptionsText(request.association), ran = associationOptionsText(associator.options());
    if (asked != associationOptionsText(AssociationOptions{}) && asked != ran) {
      throw InvalidArgument("resume: the checkpoint's run associated with " + ran + "; this run asks for " + asked +
                            " (give its options, or none: a resumed run continues the checkpoint's association)");
    }
  }
  report.association_options = associator.options();
  const bool associating = associator.options().method != AssociationMethod::Known;
  removeEarlierOutputs(out);
  report.output = runFilter(*filter, *source, progress, request.trajectory_covariances, checkpointing,
                            resume ? &*resume : nullptr, &associator, request.stop);
  if (associating || associator.options().drop_unlabelled) report.association = associator.counts();
  report.filter = checkpointing.values["filter"];
  report.info = source->info();
  source.reset();
  const std::exception_ptr failure = report.output.failure;
  // Nothing to write: no step ran, or a smoother's (whose estimate is its solve, at the end).
  const bool smoother = request.smooth || (!resume && flaggedSpec(request, request.filter).name == "batch");
  if (failure && (report.output.steps == 0 || smoother)) std::rethrow_exception(failure);
  if (report.output.steps == 0 && report.output.interrupted && !resume) {
    throw Interrupted("run interrupted before its first step: nothing written to " + out.string());
  }
  if (report.output.steps == 0 && !report.output.interrupted && !failure) throw DataError(request.dataset.string(), 0, "the dataset holds no step to run (no control or odometry)");
  try {
    finishReport(request, out, *filter, associator, start, report);
  } catch (...) {
    if (failure) std::rethrow_exception(failure);  // the run's own failure is the one reported
    throw;
  }
  return report;
}

}  // namespace seif
