#include <seif/core/errors.hpp>
#include <seif/eval/stats.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace seif {

double sampleMean(std::span<const double> xs) {
  if (xs.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (double x : xs) sum += x;
  return sum / static_cast<double>(xs.size());
}

double sampleStdDev(std::span<const double> xs) {
  if (xs.size() < 2) return 0.0;
  const double m = sampleMean(xs);
  double ss = 0.0;
  for (double x : xs) ss += (x - m) * (x - m);  // two-pass: no cancellation
  return std::sqrt(ss / static_cast<double>(xs.size() - 1));
}

double median(std::vector<double> xs) {
  if (xs.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t mid = xs.size() / 2;
  std::nth_element(xs.begin(), xs.begin() + static_cast<std::ptrdiff_t>(mid), xs.end());
  const double upper = xs[mid];
  if (xs.size() % 2 == 1) return upper;
  const double lower = *std::max_element(xs.begin(), xs.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

namespace {

// Continued fraction of I_x(a, b) (Numerical Recipes §6.4, modified Lentz), valid and fast
// for x < (a + 1) / (a + b + 2).
double betaContinuedFraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kEps = 1e-16;
  const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
  double c = 1.0;
  double d = 1.0 - qab * x / qap;
  if (std::fabs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 10000; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < kEps) return h;
  }
  return h;  // not reached for the arguments used here (t quantiles)
}

}  // namespace

double incompleteBeta(double a, double b, double x) {
  if (!(a > 0.0) || !(b > 0.0) || !(x >= 0.0 && x <= 1.0)) {
    throw InvalidArgument("incompleteBeta: needs a, b > 0 and x in [0, 1]");
  }
  if (x == 0.0 || x == 1.0) return x;
  const double log_front = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                           a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  if (x < (a + 1.0) / (a + b + 2.0)) return front * betaContinuedFraction(a, b, x) / a;
  return 1.0 - front * betaContinuedFraction(b, a, 1.0 - x) / b;
}

double studentTCdf(double t, double dof) {
  if (!(dof > 0.0)) throw InvalidArgument("studentTCdf: dof must be positive");
  if (std::isnan(t)) return t;
  if (std::isinf(t)) return t > 0 ? 1.0 : 0.0;
  const double tail = 0.5 * incompleteBeta(0.5 * dof, 0.5, dof / (dof + t * t));  // P(T > |t|)
  return t >= 0.0 ? 1.0 - tail : tail;
}

double studentTQuantile(double p, double dof) {
  if (!(p > 0.0 && p < 1.0)) throw InvalidArgument("studentTQuantile: p must be in (0, 1)");
  if (!(dof > 0.0)) throw InvalidArgument("studentTQuantile: dof must be positive");
  if (p == 0.5) return 0.0;
  if (p < 0.5) return -studentTQuantile(1.0 - p, dof);
  if (dof == 1.0) return std::tan(std::numbers::pi * (p - 0.5));  // Cauchy
  if (dof == 2.0) return (2.0 * p - 1.0) / std::sqrt(2.0 * p * (1.0 - p));
  // Bracket the root of F(t) = p on [0, hi], then bisect: F is increasing, so this always
  // converges, and 200 halvings exhaust double precision for any bracket.
  double lo = 0.0, hi = 1.0;
  while (studentTCdf(hi, dof) < p) {
    lo = hi;
    hi *= 2.0;
    if (hi > 1e300) return std::numeric_limits<double>::infinity();
  }
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (studentTCdf(mid, dof) < p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

double incompleteGamma(double a, double x) {
  if (!(a > 0.0) || !(x >= 0.0)) throw InvalidArgument("incompleteGamma: needs a > 0 and x >= 0");
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  const double log_front = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {  // series: P = e^-x x^a / Gamma(a + 1) * sum x^n / ((a+1)...(a+n))
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000 && std::fabs(term) > 1e-17 * std::fabs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return std::exp(log_front) * sum;
  }
  // Continued fraction of Q = 1 - P (Numerical Recipes §6.2, modified Lentz).
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_front) * h;
}

double chiSquareCdf(double x, double dof) {
  if (!(dof > 0.0)) throw InvalidArgument("chiSquareCdf: dof must be positive");
  return x <= 0.0 ? 0.0 : incompleteGamma(0.5 * dof, 0.5 * x);
}

double chiSquareQuantile(double p, double dof) {
  if (!(p > 0.0 && p < 1.0)) throw InvalidArgument("chiSquareQuantile: p must be in (0, 1)");
  if (!(dof > 0.0)) throw InvalidArgument("chiSquareQuantile: dof must be positive");
  double lo = 0.0, hi = std::max(1.0, 2.0 * dof);
  while (chiSquareCdf(hi, dof) < p) {
    lo = hi;
    hi *= 2.0;
  }
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chiSquareCdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Band neesBand95(std::size_t samples, int dof) {
  if (samples == 0 || dof <= 0) throw InvalidArgument("neesBand95: needs samples > 0 and dof > 0");
  const double n = static_cast<double>(samples);
  const double k = n * dof;
  return {chiSquareQuantile(0.025, k) / n, chiSquareQuantile(0.975, k) / n};
}

double ci95HalfWidth(std::span<const double> xs) {
  if (xs.size() < 2) return 0.0;
  const double n = static_cast<double>(xs.size());
  return studentTQuantile(0.975, n - 1.0) * sampleStdDev(xs) / std::sqrt(n);
}

PairedRatio pairedRatio(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size()) {
    throw InvalidArgument("pairedRatio: samples of " + std::to_string(x.size()) + " and " +
                          std::to_string(y.size()) + " values are not paired");
  }
  std::vector<double> xs, ys;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (std::isfinite(x[i]) && std::isfinite(y[i])) {
      xs.push_back(x[i]);
      ys.push_back(y[i]);
    }
  }
  PairedRatio r;
  r.pairs = xs.size();
  if (xs.empty()) {
    r.ratio = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  const double y_mean = sampleMean(ys);
  r.ratio = sampleMean(xs) / y_mean;
  std::vector<double> residual(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) residual[i] = xs[i] - r.ratio * ys[i];
  r.ci95 = ci95HalfWidth(residual) / std::abs(y_mean);
  return r;
}

Summary summarize(std::span<const double> xs) {
  Summary s;
  s.n = xs.size();
  if (xs.empty()) {
    s.mean = s.min = s.max = s.median = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  s.mean = sampleMean(xs);
  s.sd = sampleStdDev(xs);
  s.ci95 = ci95HalfWidth(xs);
  const auto [lo, hi] = std::minmax_element(xs.begin(), xs.end());
  s.min = *lo;
  s.max = *hi;
  s.median = median(std::vector<double>(xs.begin(), xs.end()));
  return s;
}

}  // namespace seif
