// The tables `seif bench` prints (include/seif/eval/bench.hpp), as text.
#include <seif/eval/bench.hpp>
#include "eval/text_format.hpp"

#include <algorithm>
#include <string>

namespace seif {
namespace {

void appendRow(std::string& text, const BenchMeasurement& m) {
  const double per = m.filter_peak_mb * 1024.0 * 1024.0 / static_cast<double>(std::max<std::size_t>(1, m.map_last));
  appendf(text, "%-6s %9d %9zu %6zu %12.1f %12.1f %10.1f %10.1f %10.0f", m.filter.c_str(), m.landmarks,
                m.map_last, m.steps, m.us_per_step_median, m.us_per_step_p90, m.peak_rss_mb,
                m.filter_peak_mb, per);
  if (m.association != "known") {
    const double correct = m.association_scored == 0 ? 0.0 : 100.0 * double(m.association_correct) / double(m.association_scored);
    appendf(text, "   %s: %.1f us/scan median, %.1f p90 over %zu scans; %.1f %% correct", m.association.c_str(),
                  m.us_association_per_scan_median, m.us_association_per_scan_p90, m.scans, correct);
  }
  appendf(text, "\n");
}

void appendSkipped(std::string& text, const std::string& filter, int n, const std::string& why) {
  appendf(text, "%-6s %9d   skipped: %s\n", filter.c_str(), n, why.c_str());
}

}  // namespace

std::string benchHeaderText() {
  std::string text;
  appendf(text, "%-6s %9s %9s %6s %12s %12s %10s %10s %10s\n", "filter", "N", "mapped", "steps",
                "median us", "p90 us", "peak MB", "filter MB", "B/landmark");
  return text;
}


std::string benchRowText(const BenchRow& row) {
  std::string text;
  if (row.measurement) {
    appendRow(text, *row.measurement);
  } else {
    appendSkipped(text, row.filter, row.landmarks, row.skipped);
  }
  return text;
}

std::string benchTargetsText(const BenchTargets& t) {
  std::string text;
  if (const auto& g = t.seif_growth) {
    appendf(text, "SEIF median at N=%d / at N=%d: %.1f / %.1f us = %.2fx (target <= 1.5x): %s\n", g->to_landmarks,
                  g->from_landmarks, g->to_us, g->from_us, g->ratio, g->met ? "met" : "NOT met");
  }
  if (const auto& g = t.seif_association_growth) {
    appendf(text, "SEIF association per scan at N=%d / at N=%d: %.1f / %.1f us = %.2fx (target <= 1.5x): %s\n",
                  g->to_landmarks, g->from_landmarks, g->to_us, g->from_us, g->ratio, g->met ? "met" : "NOT met");
  }
  if (const auto& s = t.ekf_over_seif) {
    appendf(text, "EKF / SEIF median at N=%d: %.1f / %.1f us = %.*fx (target >= 100x): %s\n", s->landmarks,
                  s->ekf_us, s->seif_us, s->ratio >= 10.0 ? 0 : 2, s->ratio, s->met ? "met" : "NOT met");
  }
  if (!t.seif_bytes_per_landmark.empty()) {
    appendf(text, "SEIF memory per landmark (filter peak / mapped):");
    for (const auto& [n, bytes] : t.seif_bytes_per_landmark) appendf(text, " %.0f B at N=%d;", bytes, n);
    appendf(text, "\n");
  }
  return text;
}

std::string interruptedText(const BenchReport& report) {
  const std::size_t n = report.rows.size();
  return "bench interrupted after " + std::to_string(n) + (n == 1 ? " case" : " cases");
}

std::string benchSummaryText(const BenchReport& report) {
  std::string text = benchHeaderText();
  for (const BenchRow& row : report.rows) text += benchRowText(row);
  return text + benchTargetsText(report.targets);
}

}  // namespace seif
