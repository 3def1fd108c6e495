#pragma once
// One scan's association problem, as the strategies see it (nn.cpp,
// jcbb.cpp): each observation's individually compatible landmarks with their
// Mahalanobis distances, and for JCBB the joint marginal of the pose and every candidate.
#include <seif/filters/slam_filter.hpp>

#include <cstddef>
#include <unordered_map>
#include <vector>

namespace seif {

struct Pairing {
  int observation = -1;  ///< index into the scan's observations
  int landmark = -1;     ///< landmark id
  double d2 = 0.0;       ///< squared Mahalanobis distance of the innovation
};

struct ScanProblem {
  const SlamFilter* filter = nullptr;
  const MeasurementModel* sensor = nullptr;
  const std::vector<Observation>* observations = nullptr;
  std::vector<std::vector<Pairing>> compatible;  ///< per observation, inside the accept gate
  double accept_d2 = 0.0;                        ///< the accept gate (2 dof)
  double accept_probability = 0.99;              ///< for the joint gate's chi-square(2k)
  MarginalMode marginal = MarginalMode::Exact;
  /// The joint marginal of the pose (first 3 rows) and every candidate of the scan, and
  /// where each candidate's 2 rows start in it.
  Marginal joint;
  std::unordered_map<int, Eigen::Index> column;
  /// JCBB's joint gates, chi-square(2k) at accept_probability by k, kept across scans (the
  /// search extends it as far as a scan needs).
  std::vector<double>* joint_gates = nullptr;
};

/// Per observation: the landmark id it is paired with, or -1.
/// nn: pairings inside the gate taken greedily by distance, each landmark at most once.
std::vector<int> assignNearestNeighbour(const ScanProblem& scan);
/// jcbb: the hypothesis with the most pairings (ties: the smallest joint distance) whose
/// joint innovation passes the chi-square(2k) gate at each of its prefixes in the search
/// order (observations by their nearest candidate's distance), searched depth first at most
/// `max_nodes` nodes. When the bound stops the search (*truncated), the best hypothesis
/// found so far is returned, partial ones (a dive cut short) included.
std::vector<int> assignJcbb(const ScanProblem& scan, std::size_t max_nodes, bool* truncated);

/// The p-quantile of chi-square with 2k degrees of freedom (closed-form CDF, bisection).
double chiSquareEvenQuantile(double p, int k);

}  // namespace seif
