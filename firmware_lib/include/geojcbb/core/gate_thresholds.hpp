// core: chi-square thresholds of the individual test (2 dof) and of the joint test (2p dof for p
// pairings), computed once per configuration, or given raw by the caller.
#pragma once

#include <array>
#include <cmath>
#include <limits>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

/// @tparam MaxPairs  most pairings a hypothesis can hold (the observation capacity)
template <typename T, int MaxPairs>
struct GateThresholds {
  T individual = std::numeric_limits<T>::quiet_NaN();  ///< d2_ij <= individual (2 dof)
  /// joint[p]: a hypothesis with p pairings is jointly compatible when D2 <= joint[p] (2p dof).
  std::array<T, MaxPairs + 1> joint{};

  /// Thresholds from confidence levels, e.g. 0.99 and 0.99 (chi2inv(p, dof)).
  /// @return kOk; kInvalidInput for a level outside (0, 1); kNoConvergence from chi2_inv.
  [[nodiscard]] static Status from_confidence(double individual_p, double joint_p, GateThresholds& out) {
    GateThresholds g;
    double v = 0.0;
    Status s = chi2_inv(individual_p, 2, v);
    if (s != Status::kOk) return s;
    g.individual = static_cast<T>(v);
    g.joint[0] = T(0);
    for (int p = 1; p <= MaxPairs; ++p) {  // <= MaxPairs
      s = chi2_inv(joint_p, 2 * p, v);
      if (s != Status::kOk) return s;
      g.joint[p] = static_cast<T>(v);
    }
    out = g;
    return Status::kOk;
  }

  /// Raw thresholds are accepted when finite, positive and non-decreasing in p (a hypothesis that
  /// gains a pairing never gets a stricter bound).
  [[nodiscard]] bool valid() const {
    if (!(std::isfinite(individual) && individual > T(0))) return false;
    for (int p = 1; p <= MaxPairs; ++p) {  // <= MaxPairs
      if (!(std::isfinite(joint[p]) && joint[p] > T(0) && joint[p] >= joint[p - 1])) return false;
    }
    return true;
  }
};

}  // namespace geojcbb
