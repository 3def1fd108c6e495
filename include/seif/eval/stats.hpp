#pragma once
// Small-sample statistics for Monte-Carlo experiments (`seif paper`): sample mean, sample
// standard deviation, the Student-t quantile and the 95 % confidence interval of a mean or
// of a ratio of paired means.
#include <cstddef>
#include <span>
#include <vector>

namespace seif {

/// Arithmetic mean; NaN for an empty sample.
double sampleMean(std::span<const double> xs);

/// Sample standard deviation with Bessel's correction (divides by n - 1); 0 for n < 2.
double sampleStdDev(std::span<const double> xs);

/// Median (the mean of the two middle values for an even count); NaN for an empty sample.
/// Takes its argument by value: it is partially sorted.
double median(std::vector<double> xs);

/// Regularized incomplete beta function I_x(a, b) for a, b > 0 and x in [0, 1]
/// (continued fraction, modified Lentz; absolute accuracy ~1e-14).
double incompleteBeta(double a, double b, double x);

/// Cumulative distribution function of Student's t with `dof` > 0 degrees of freedom:
/// F(t) = 1 - I_{dof/(dof+t^2)}(dof/2, 1/2) / 2 for t >= 0, symmetric for t < 0.
double studentTCdf(double t, double dof);

/// The p-quantile of Student's t with `dof` > 0 degrees of freedom, p in (0, 1): closed
/// forms for 1 and 2 degrees of freedom, otherwise the inverse of studentTCdf() by
/// safeguarded Newton/bisection (relative accuracy ~1e-12). Throws InvalidArgument
/// outside the domain.
double studentTQuantile(double p, double dof);

/// Regularized lower incomplete gamma function P(a, x) for a > 0, x >= 0 (series for
/// x < a + 1, continued fraction otherwise; absolute accuracy ~1e-14).
double incompleteGamma(double a, double x);

/// Cumulative distribution function of the chi-square distribution: P(dof / 2, x / 2).
double chiSquareCdf(double x, double dof);

/// The p-quantile of the chi-square distribution with `dof` > 0 degrees of freedom, p in
/// (0, 1), by bisection of chiSquareCdf() (relative accuracy ~1e-12).
double chiSquareQuantile(double p, double dof);

/// The two-sided 95 % band of the mean of `samples` independent NEES values of `dof`
/// degrees of freedom each (Bar-Shalom, Li, Kirubarajan 2001, §5.4.2): the sum is
/// chi-square with samples * dof degrees of freedom, so the band is
/// [chi2_{0.025}(n d) / n, chi2_{0.975}(n d) / n].
struct Band {
  double lo = 0.0;
  double hi = 0.0;
};
Band neesBand95(std::size_t samples, int dof);

/// Half-width of the two-sided 95 % confidence interval of the mean of an i.i.d. sample:
/// t_{0.975, n-1} * s / sqrt(n), s = sampleStdDev(). 0 for n < 2 (no interval: undefined).
double ci95HalfWidth(std::span<const double> xs);

/// The ratio of the means of two paired samples (x_i and y_i from the same run), R =
/// mean(x) / mean(y) over the pairs where both are finite, and the half-width of its 95 %
/// confidence interval by the delta method: with the residuals d_i = x_i - R y_i,
/// t_{0.975, n-1} sd(d) / (sqrt(n) mean(y)) (the paper's "error ratio to the EKF"; a ratio
/// of means, not a mean of per-run ratios, which a few runs near zero would dominate).
/// Half-width 0 for fewer than two pairs; ratio NaN for none. InvalidArgument when the
/// samples differ in length.
struct PairedRatio {
  double ratio = 0.0;
  double ci95 = 0.0;
  std::size_t pairs = 0;  ///< pairs where both values are finite
};
PairedRatio pairedRatio(std::span<const double> x, std::span<const double> y);

/// Everything the tables print about one sample.
struct Summary {
  std::size_t n = 0;
  double mean = 0.0;
  double sd = 0.0;    ///< sample standard deviation (n - 1)
  double ci95 = 0.0;  ///< half-width of the 95 % confidence interval of the mean
  double min = 0.0;
  double max = 0.0;
  double median = 0.0;
};

Summary summarize(std::span<const double> xs);

}  // namespace seif
