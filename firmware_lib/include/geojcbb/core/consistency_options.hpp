// core: the options of the pose-free consistency stage as plain data: which pairings become
// graph nodes (a wide individual gate, or every candidate in the local region), the pairwise
// distance gate (chi-square, 1 dof) and the max-clique node budget (<= kMaxCliqueSearchNodes).
// Reference: Bailey, "Mobile robot localisation and mapping in extensive outdoor environments"
// (CCDA, 2002); Mangelson et al., "Pairwise consistent measurement set maximization" (PCM, 2018).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/settings.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

/// Which (observation, candidate) pairings become nodes of the consistency graph.
enum class PairingGate : std::uint8_t {
  kWide,            ///< individual d2 <= wide_d2 (the individual gate at a much higher confidence)
  kEveryCandidate,  ///< every candidate in the local region (all when the region is off): no pose trust
};

/// Compile-time cap on a max-clique search's run-time node budget: the worst case of one call.
constexpr std::uint32_t kMaxCliqueSearchNodes = 1000000;

/// Default search nodes of one consistency call (docs/results/consistency.md: random 64-node graphs need far
/// fewer; consistency graphs are sparse outside their true clique).
constexpr std::uint32_t kDefaultCliqueBudget = 20000;

template <typename T>
struct ConsistencyOptions {
  PairingGate pairing_gate = PairingGate::kWide;
  T wide_d2 = std::numeric_limits<T>::quiet_NaN();  ///< kWide: individual d2 threshold (2 dof)
  T pair_d2 = std::numeric_limits<T>::quiet_NaN();  ///< pairwise distance test threshold (1 dof)
  /// Local region (2019 paper, eq. 5): only candidates with predicted range < local_radius_m.
  bool local_region = false;
  T local_radius_m = T(0);  ///< [m]; used when local_region is on
  /// Max-clique search nodes, 0 .. kMaxCliqueSearchNodes (0: the greedy clique only).
  std::uint32_t node_budget = kDefaultCliqueBudget;

  /// Sets wide_d2 = chi2inv(wide_p, 2) and pair_d2 = chi2inv(pair_p, 1), e.g. 0.99999 and 0.999.
  /// @return kOk; kInvalidInput for a level outside (0, 1); kNoConvergence from chi2_inv. Nothing is
  ///         written unless kOk.
  [[nodiscard]] Status set_confidence(double wide_p, double pair_p) {
    double wide = 0.0;
    double pair = 0.0;
    Status s = chi2_inv(wide_p, 2, wide);
    if (s != Status::kOk) return s;
    s = chi2_inv(pair_p, 1, pair);
    if (s != Status::kOk) return s;
    wide_d2 = static_cast<T>(wide);
    pair_d2 = static_cast<T>(pair);
    return Status::kOk;
  }

  /// Thresholds finite and positive (wide_d2 only when used), a positive radius when the region is
  /// on, the budget within its cap.
  [[nodiscard]] bool valid() const {
    if (!(std::isfinite(pair_d2) && pair_d2 > T(0))) return false;
    if (pairing_gate == PairingGate::kWide && !(std::isfinite(wide_d2) && wide_d2 > T(0))) return false;
    if (pairing_gate != PairingGate::kWide && pairing_gate != PairingGate::kEveryCandidate) return false;
    if (local_region && !(std::isfinite(local_radius_m) && local_radius_m > T(0))) return false;
    return node_budget <= kMaxCliqueSearchNodes;
  }

  /// The candidate with predicted measurement h is in the local region.
  bool in_region(const Vec2<T>& h) const { return !local_region || h.x() < local_radius_m; }
};

/// ConsistencyOptions' members that are options of the table, (member, option): local_region is the
/// preset's switch, pairing_gate and node_budget the stage's (core/association_config.hpp,
/// consistency_options).
#define GEOJCBB_CONSISTENCY_OPTIONS(F) \
  F(wide_d2, consistency_wide_d2) F(pair_d2, consistency_pair_d2) F(local_radius_m, local_radius_m)
/// out's options of the table from the settings `in` (core/settings.hpp, GEOJCBB_BIND_OPTION).
template <class In, typename T>
void bind_options(const In& in, ConsistencyOptions<T>& out) {
  GEOJCBB_CONSISTENCY_OPTIONS(GEOJCBB_BIND_OPTION)
}

}  // namespace geojcbb
