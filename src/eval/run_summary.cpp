// The report `seif run` prints (runSummary(), include/seif/eval/run_dataset.hpp).
#include <seif/eval/run_dataset.hpp>
#include "eval/text_format.hpp"

#include <cstdio>
#include <string>

namespace seif {
namespace {

std::string metres(const std::optional<double>& v) {
  return v ? formatted("%.4f", *v) : "n/a";
}

}  // namespace

std::string runSummary(const RunRequest& request, const RunReport& r, const std::filesystem::path& out_dir) {
  std::string text;
  const RunOutput& out = r.output;
  if (!request.resume.empty()) appendf(text, "resumed from %s\n", request.resume.string().c_str());
  appendf(text, "%s on %s (%s): %zu steps, %zu landmarks, %.1f us/step\n", r.filter.c_str(),
                request.dataset.string().c_str(), r.info.format.c_str(), out.steps, r.landmarks,
                out.steps == 0 ? 0.0 : 1e6 * out.seconds / static_cast<double>(out.steps));
  appendf(text, "  motion: %s\n  sensor: %s\n", r.info.motion->describe().c_str(), r.info.sensor->describe().c_str());
  for (const NoiseSetting& n : r.info.noise) {
    const std::string value = n.value ? formatted("%g", *n.value) : "per record";
    appendf(text, "  noise %-15s %-10s %-14s (%s)\n", n.name.c_str(), value.c_str(), n.unit.c_str(), n.source.c_str());
  }
  appendf(text, "  start pose (%.3f, %.3f, %.3f): %s\n", r.info.start_pose.x(), r.info.start_pose.y(),
                r.info.start_pose.z(), r.info.start_pose_source.c_str());
  const RunErrors& e = r.errors;
  if (r.info.has_groundtruth || !r.info.landmarks.empty()) {
    appendf(text, "  aligned:   landmark RMSE %s m | ATE %s m | dead-reckoning ATE %s m\n",
                  metres(e.landmark).c_str(), metres(e.ate).c_str(), metres(e.dead_reckoning_ate).c_str());
    appendf(text, "  unaligned: landmark RMSE %s m | ATE %s m | dead-reckoning ATE %s m | links %zu\n",
                  metres(e.landmark_unaligned).c_str(), metres(e.ate_unaligned).c_str(),
                  metres(e.dead_reckoning_ate_unaligned).c_str(), out.final_stats.links);
  }
  if (r.info.has_gps) {
    appendf(text, "  GPS (%zu fixes, aligned): trajectory RMSE %s m (median %s m; %s m without the %zu that jump) | "
                  "dead reckoning %s m\n",
                  e.gps_fixes, metres(e.gps).c_str(), metres(e.gps_median).c_str(),
                  metres(e.gps_without_jumps).c_str(), e.gps_jumps, metres(e.dead_reckoning_gps).c_str());
  }
  const double kappa = out.final_stats.information_scale;
  if (kappa > kForgottenInformationScale) {
    appendf(text, "  warning: information scaled down %.3g times (seif:rho, sparsify=conservative): the first "
                  "steps, and the start prior, now weigh less than 1/%.0g of the newest\n",
                  kappa, kForgottenInformationScale);
  } else if (kappa != 1.0) {
    appendf(text, "  information scaled down %.3g times (seif:rho, sparsify=conservative)\n", kappa);
  }
  appendf(text, "  time: filter %.2f s | read and filter %.2f s | trajectory and map with covariances %.2f s\n",
                out.seconds, r.seconds_wall, r.seconds_outputs);
  for (const auto& [reason, count] : out.dropped) {
    if (count > 0) appendf(text, "  dropped %zu records: %s\n", count, reason.c_str());
  }
  if (r.smoother) {
    const SmootherReport& b = *r.smoother;
    appendf(text, "  batch from %s: %d poses, %d landmarks, %d constraints; 0.5 chi2 %.6g -> %.6g in %d iterations, "
                  "%.3f s (linearise %.3f, factorise %.3f, solve %.3f); |gradient| %.3g (from %.3g)\n",
                  b.init.c_str(), b.poses, b.landmarks, b.constraints, b.initial_cost, b.final_cost, b.iterations,
                  b.solve_seconds, b.linearize_seconds, b.factorize_seconds, b.step_seconds, b.gradient_norm,
                  b.initial_gradient_norm);
    if (!b.converged) {
      appendf(text, "  WARNING: the batch stopped at its iteration limit without converging (from %s: try another --init)\n",
                    b.init.c_str());
    }
  }
  if (r.filter_errors) {
    const RunErrors& f = *r.filter_errors;
    appendf(text, "  the filter before smoothing: landmark RMSE %s m | ATE %s m | GPS RMSE %s m | map %s m from the batch's\n",
                  metres(f.landmark).c_str(), metres(f.ate).c_str(), metres(f.gps).c_str(),
                  metres(r.filter_map_distance).c_str());
    if (r.filter_trajectory_distance) {
      const Vec2& d = *r.filter_trajectory_distance;
      appendf(text, "  the filter's trajectory from the batch's: RMS %s m, median %s m\n", metres(d(0)).c_str(),
                    metres(d(1)).c_str());
    }
  }
  const std::string association(associationMethodName(r.association_options.method));  // a resumed run's: the checkpoint's
  if (r.association && association == "known") {
    appendf(text, "  association known: %zu observations, %zu without a landmark id dropped\n", r.association->observations,
                  r.association->unlabelled_dropped);
  } else if (r.association) {
    const AssociationCounts& a = *r.association;
    appendf(text, "  association %s: %zu observations; %zu of %zu with a truth id correct (%.2f %%), %zu wrong; "
                  "%zu without one (%zu matched to a labelled landmark)\n",
                  association.c_str(), a.observations, a.correct, a.scored,
                  a.scored == 0 ? 0.0 : 100.0 * double(a.correct) / double(a.scored), a.wrong, a.unlabelled,
                  a.unlabelled_matched);
    appendf(text, "    %zu landmarks started, %zu provisional removed, %zu merged, %zu ambiguous dropped; %zu landmarks at "
                  "the end (%zu spurious, %zu duplicates%s); %.2f s associating%s\n",
                  a.new_landmarks, a.provisional_removed, a.merged, a.ambiguous_dropped, a.landmarks_final, a.spurious_landmarks,
                  a.duplicate_landmarks,
                  a.provisional_final > 0 ? (", " + std::to_string(a.provisional_final) + " still provisional").c_str() : "",
                  a.seconds,
                  a.jcbb_truncated > 0 ? (", " + std::to_string(a.jcbb_truncated) + " JCBB searches truncated").c_str() : "");
    if (const auto& c = r.association_ceiling; c && c->observations > 0) {
      appendf(text, "    ceiling (the true map seen from the true pose): %.2f %% individually, %.2f %% jointly of %zu "
                    "labelled observations; this run %.2f %% of them\n",
                    100.0 * double(c->individual) / double(c->observations),
                    100.0 * double(c->joint) / double(c->observations), c->observations,
                    100.0 * double(a.correct) / double(c->observations));
    }
  }
  if (out.rejected_observations > 0) {
    appendf(text, "  rejected %zu gross outlier observation%s (beyond %g sigma of the measurement noise)\n",
                  out.rejected_observations, out.rejected_observations == 1 ? "" : "s", request.outlier_gate);
  }
  const bool associating = r.association_options.method != AssociationMethod::Known;  // as run_dataset writes it
  const bool recorded = associating && out.associations_from == 0;
  std::string extra;  // in the order run_dataset writes them
  if (r.filter_errors) extra += ",trajectory_filter.tum,map_filter.csv";
  if (!out.gps.empty()) extra += ",gps.csv";
  if (!out.groundtruth.empty()) extra += ",groundtruth.tum";
  if (!r.info.landmarks.empty()) extra += ",landmarks_groundtruth.csv";
  if (recorded) extra += ",associations.csv";
  if (request.trajectory_covariances) extra += ",trajectory_cov.csv";
  appendf(text, "  wrote %s/{trajectory.tum,dead_reckoning.tum,map.csv,metrics.json%s}\n", out_dir.string().c_str(),
                extra.c_str());
  if (associating && !recorded) {
    appendf(text, "  no associations.csv: the checkpoint resumed (at step %zu) was written before runs recorded "
                  "their associations\n", out.associations_from);
  }
  return text;
}

}  // namespace seif
