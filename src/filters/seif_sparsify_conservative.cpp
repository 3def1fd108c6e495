// The conservative sparsification (SeifOptions::Sparsify::Conservative; docs/consistency.md,
// "Conservative sparsification"): the paper's rule (seif_sparsify_paper.cpp, eq. 44-51),
// then the whole posterior's information scaled down just enough that it claims no more
// than before. The journal paper's knob H <- (1 - rho) H (IJRR 2004, §5.3, with H0 = 0),
// with rho chosen per sparsification rather than fixed.
//
// The rule changes the gathered block [x, Y+, Y0] by E = H~ - H. With Sigma the block's
// marginal covariance, c = lambda_max(L^T E L) (Sigma = L L^T, overclaimRatio) is the least c
// with E <= c H, so (H + E) / (1 + c) <= H: nothing is claimed that H did not hold. Sigma is
// the local marginal over options.blanket variables (O(1)); it conditions on the rest, so the
// guarantee holds for every change of the blanket's variables with the rest held (with the
// whole map in the blanket, for every change). The scale is kept as kappa (the store holds
// kappa H): the mean H^-1 b is unchanged and nothing in the store is rewritten.
#include "filters/seif_slam.hpp"

#include <seif/core/errors.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace seif {

namespace {

std::string shortNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

/// When the rule keeps claiming much more than H holds (the standard Jacobians' SEIF with few
/// active landmarks), kappa grows without limit: every later step's information outweighs
/// the old by kappa, and H loses the start prior that fixes the global frame.
[[noreturn]] void rethrowLost(const NumericError& e, long step, double kappa) {
  throw NumericError("seif: conservative sparsification after " + std::to_string(step) +
                     " motion updates (information scaled down " + shortNumber(kappa) + " times so far): " + e.what() +
                     "; the paper's rule claimed too much to keep: more active landmarks, or "
                     "linearization=invariant (docs/consistency.md)");
}

}  // namespace

void SeifSlam::beginConservativeSparsification() {
  // Before gather(): the block's marginal from the store's H (kappa H: Sigma / kappa).
  std::vector<int> vars;
  vars.reserve(order_.size() + 1);
  vars.push_back(-1);
  vars.insert(vars.end(), order_.begin(), order_.end());
  try {
    overclaim_sigma_ = localCovariance(vars);
  } catch (const NumericError& e) {
    rethrowLost(e, store_.step(), information_scale_);
  }
}

void SeifSlam::endConservativeSparsification() {
  const LocalMatrix& H = store_.localH();  // after eq. (44-51), before scatter()
  double c = 0.0;
  try {
    c = overclaimRatio(H - overclaim_h_, overclaim_sigma_);
  } catch (const NumericError& e) {
    rethrowLost(e, store_.step(), information_scale_);
  }
  if (!(c < 1e12)) {  // also NaN
    throw NumericError("seif: conservative sparsification after " + std::to_string(store_.step()) +
                       " motion updates: the rule claims " + shortNumber(c) + " times the information the block held");
  }
  if (c > 0.0) {
    information_scale_ *= 1.0 + c;  // H / kappa <- H / (kappa (1 + c))
    ++scalings_;
  }
}

}  // namespace seif
