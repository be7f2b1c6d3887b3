// tests/support: an exhaustive-search oracle for JCBB, independent of the library's gate and
// incremental factor. It recomputes individual compatibility and every joint d2 from scratch in long
// double (explicit S_H, LDLT), and enumerates the space JCBB searches: every hypothesis whose
// prefixes, in JCBB's observation order, pass the joint test.
// Rounding: a test value within `margin` (relative) of its threshold is "borderline". The oracle runs
// twice, treating borderline as fail (strict) and as pass (loose); a problem where the two runs agree
// has one exact answer.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "geojcbb/associate.hpp"

namespace geojcbb::test {

struct OracleResult {
  int max_pairings = 0;
  long double min_d2 = 0;       ///< smallest joint d2 among hypotheses with max_pairings
  int max_pairings_whole = -1;  ///< most pairings of any hypothesis passing as a whole (-1: not run)
  std::uint64_t hypotheses = 0;
};

template <typename T, class B>
class Oracle {
 public:
  using LD = long double;
  Oracle(const Observations<T, B>& obs, const Prediction<T, B>& pred, const AssociationConfig<T, B>& cfg,
         long double margin, bool loose)
      : obs_(obs), pred_(pred), cfg_(cfg), margin_(margin), loose_(loose) {}

  /// Whether d2 passes threshold thr under this run's borderline rule.
  bool passes(LD d2, LD thr) const {
    if (d2 <= thr * (1 - margin_)) return true;
    if (d2 > thr * (1 + margin_)) return false;
    borderline_ = true;
    return loose_;
  }
  bool saw_borderline() const { return borderline_; }

  LD individual_d2(int i, int j) const {
    Eigen::Matrix<LD, 2, 2> S = pred_.C.block(j, j).template cast<LD>() + obs_.R[i].template cast<LD>();
    Eigen::Matrix<LD, 2, 1> nu = nu_of(i, j);
    return nu.dot(S.ldlt().solve(nu));
  }

  /// Joint d2 of pairs (obs i_k, cand j_k), from an explicit S_H.
  LD joint_d2(const std::vector<std::pair<int, int>>& pairs) const {
    const int n = static_cast<int>(pairs.size());
    if (n == 0) return 0;
    Eigen::Matrix<LD, Eigen::Dynamic, Eigen::Dynamic> S(2 * n, 2 * n);
    Eigen::Matrix<LD, Eigen::Dynamic, 1> nu(2 * n);
    for (int a = 0; a < n; ++a) {
      nu.template segment<2>(2 * a) = nu_of(pairs[a].first, pairs[a].second);
      for (int b = 0; b < n; ++b) {
        S.template block<2, 2>(2 * a, 2 * b) = pred_.C.block(pairs[a].second, pairs[b].second).template cast<LD>();
      }
      S.template block<2, 2>(2 * a, 2 * a) += obs_.R[pairs[a].first].template cast<LD>();
    }
    return nu.dot(S.ldlt().solve(nu));
  }

  /// Enumerates JCBB's space. `whole_limit`: also enumerate every hypothesis (no prefix rule) when
  /// the space has at most this many leaves.
  OracleResult run(std::uint64_t whole_limit) {
    const int m = obs_.count;
    cands_.assign(m, {});
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < pred_.count; ++j) {
        if (passes(individual_d2(i, j), static_cast<LD>(cfg_.gate.individual))) cands_[i].push_back(j);
      }
    }
    order_.clear();
    for (int i = 0; i < m; ++i) {
      if (!cands_[i].empty()) order_.push_back(i);
    }
    if (cfg_.order_fewest_candidates_first) {
      std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) { return cands_[a].size() < cands_[b].size(); });
    }
    OracleResult r;
    r.min_d2 = std::numeric_limits<LD>::infinity();
    std::vector<std::pair<int, int>> pairs;
    prefix_search(0, pairs, r);
    if (r.max_pairings == 0) r.min_d2 = 0;
    std::uint64_t leaves = 1;
    for (int i : order_) {
      leaves *= cands_[i].size() + 1;
      if (leaves > whole_limit) break;
    }
    if (leaves <= whole_limit) {
      pairs.clear();
      r.max_pairings_whole = 0;
      whole_search(0, pairs, r);
    }
    return r;
  }

  /// Is this hypothesis (per observation: candidate or -1) in JCBB's space, i.e. do its prefixes in
  /// JCBB's order all pass? (Call after run().)
  bool prefixes_pass(const std::array<std::int16_t, B::kMaxObservations>& hyp) const {
    std::vector<std::pair<int, int>> pairs;
    for (int i : order_) {
      if (hyp[i] < 0) continue;
      pairs.emplace_back(i, hyp[i]);
      if (!passes(joint_d2(pairs), static_cast<LD>(cfg_.gate.joint[pairs.size()]))) return false;
    }
    return true;
  }

 private:
  Eigen::Matrix<LD, 2, 1> nu_of(int i, int j) const {
    Eigen::Matrix<LD, 2, 1> nu;
    nu[0] = static_cast<LD>(obs_.z[i].x()) - static_cast<LD>(pred_.h[j].x());
    LD b = static_cast<LD>(obs_.z[i].y()) - static_cast<LD>(pred_.h[j].y());
    const LD pi = 3.14159265358979323846264338327950288L;
    while (b > pi) b -= 2 * pi;
    while (b <= -pi) b += 2 * pi;
    nu[1] = b;
    return nu;
  }
  bool taken(const std::vector<std::pair<int, int>>& pairs, int j) const {
    for (const auto& pr : pairs) {
      if (pr.second == j) return true;
    }
    return false;
  }
  void prefix_search(std::size_t level, std::vector<std::pair<int, int>>& pairs, OracleResult& r) {
    if (level == order_.size()) {
      ++r.hypotheses;
      const int p = static_cast<int>(pairs.size());
      const LD d2 = joint_d2(pairs);
      if (p > r.max_pairings) {
        r.max_pairings = p;
        r.min_d2 = d2;
      } else if (p == r.max_pairings && d2 < r.min_d2) {
        r.min_d2 = d2;
      }
      return;
    }
    const int i = order_[level];
    for (int j : cands_[i]) {
      if (cfg_.mutual_exclusion && taken(pairs, j)) continue;
      pairs.emplace_back(i, j);
      if (passes(joint_d2(pairs), static_cast<LD>(cfg_.gate.joint[pairs.size()]))) {
        prefix_search(level + 1, pairs, r);
      }
      pairs.pop_back();
    }
    prefix_search(level + 1, pairs, r);
  }
  void whole_search(std::size_t level, std::vector<std::pair<int, int>>& pairs, OracleResult& r) {
    if (level == order_.size()) {
      const int p = static_cast<int>(pairs.size());
      if (p > r.max_pairings_whole && passes(joint_d2(pairs), static_cast<LD>(cfg_.gate.joint[p]))) {
        r.max_pairings_whole = p;
      }
      return;
    }
    const int i = order_[level];
    for (int j : cands_[i]) {
      if (cfg_.mutual_exclusion && taken(pairs, j)) continue;
      pairs.emplace_back(i, j);
      whole_search(level + 1, pairs, r);
      pairs.pop_back();
    }
    whole_search(level + 1, pairs, r);
  }

  const Observations<T, B>& obs_;
  const Prediction<T, B>& pred_;
  const AssociationConfig<T, B>& cfg_;
  LD margin_;
  bool loose_;
  mutable bool borderline_ = false;
  std::vector<std::vector<int>> cands_;
  std::vector<int> order_;
};

}  // namespace geojcbb::test
