// core: chi-square quantiles chi2inv(p, k) for the individual and joint compatibility gates.
// Computed in double (once, when a configuration is applied), by safeguarded Newton iteration on the
// regularized lower incomplete gamma function P(k/2, x/2): series for x < a + 1, Lentz's continued
// fraction otherwise (Numerical Recipes 6.2). ln Gamma(k/2) is exact by recursion from Gamma(1/2) and
// Gamma(1). Bounds: kMaxGammaTerms terms per evaluation, kMaxNewtonIterations Newton steps.
#pragma once

#include <cmath>
#include <limits>

#include "geojcbb/core/status.hpp"

namespace geojcbb {
namespace chi2_detail {

constexpr int kMaxGammaTerms = 2000;
constexpr int kMaxNewtonIterations = 200;
constexpr int kMaxDof = 4096;

/// ln Gamma(k / 2) for 1 <= k <= kMaxDof.  Loop bound: k / 2 <= 2048.
inline double ln_gamma_half(int k) {
  double a = (k % 2 == 0) ? 1.0 : 0.5;
  double ln_g = (k % 2 == 0) ? 0.0 : 0.5 * std::log(3.14159265358979323846);
  for (; 2.0 * a < static_cast<double>(k); a += 1.0) {  // <= k / 2 iterations
    ln_g += std::log(a);
  }
  return ln_g;
}

/// P(a, x), the regularized lower incomplete gamma function; false if the bound ran out.
inline bool gamma_p(double a, double x, double ln_gamma_a, double& out) {
  constexpr double kEps = 1e-16;
  constexpr double kTiny = 1e-300;
  if (x <= 0.0) {
    out = 0.0;
    return true;
  }
  const double log_prefactor = -x + a * std::log(x) - ln_gamma_a;
  if (x < a + 1.0) {
    double ap = a;
    double del = 1.0 / a;
    double sum = del;
    for (int n = 0; n < kMaxGammaTerms; ++n) {  // <= kMaxGammaTerms
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * kEps) {
        out = sum * std::exp(log_prefactor);
        return true;
      }
    }
    return false;
  }
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i <= kMaxGammaTerms; ++i) {  // <= kMaxGammaTerms
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < kEps) {
      out = 1.0 - std::exp(log_prefactor) * h;
      return true;
    }
  }
  return false;
}

}  // namespace chi2_detail

/// Chi-square cumulative distribution F(x; dof).
/// @return kOk; kInvalidInput for dof outside [1, 4096] or non-finite x; kNoConvergence if the
///         series/fraction bound ran out (not observed for dof <= 4096).
[[nodiscard]] inline Status chi2_cdf(double x, int dof, double& out) {
  if (dof < 1 || dof > chi2_detail::kMaxDof || !std::isfinite(x)) return Status::kInvalidInput;
  const double a = 0.5 * dof;
  double p = 0.0;
  if (!chi2_detail::gamma_p(a, 0.5 * x, chi2_detail::ln_gamma_half(dof), p)) {
    return Status::kNoConvergence;
  }
  out = p;
  return Status::kOk;
}

/// Chi-square quantile: the x with F(x; dof) = p.
/// @return kOk; kInvalidInput for p outside (0, 1) or dof outside [1, 4096]; kNoConvergence if the
///         iteration bound ran out.
[[nodiscard]] inline Status chi2_inv(double p, int dof, double& out) {
  if (!(p > 0.0 && p < 1.0) || dof < 1 || dof > chi2_detail::kMaxDof) return Status::kInvalidInput;
  const double a = 0.5 * dof;
  const double ln_g = chi2_detail::ln_gamma_half(dof);
  const double ln_norm = a * std::log(2.0) + ln_g;
  double lo = 0.0;
  double hi = std::numeric_limits<double>::infinity();
  double x = static_cast<double>(dof);
  for (int it = 0; it < chi2_detail::kMaxNewtonIterations; ++it) {  // <= kMaxNewtonIterations
    double cdf = 0.0;
    if (!chi2_detail::gamma_p(a, 0.5 * x, ln_g, cdf)) return Status::kNoConvergence;
    const double f = cdf - p;
    if (f < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const double pdf = std::exp((a - 1.0) * std::log(x) - 0.5 * x - ln_norm);
    double next = (pdf > 0.0) ? x - f / pdf : x;
    if (!(next > lo && next < hi) || pdf <= 0.0) {
      next = std::isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * x;  // bisect, or expand the bracket
    }
    if (std::abs(next - x) <= 1e-13 * x) {
      out = next;
      return Status::kOk;
    }
    x = next;
  }
  return Status::kNoConvergence;
}

}  // namespace geojcbb
