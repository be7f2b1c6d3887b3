// cluster: k-means (KJCBB's grouping; Lloyd's algorithm) over the observations' points.
// Start: farthest-first seeds (groups.hpp). Stops when no label changes or after max_iterations
// (<= kMaxKMeansIterations). An emptied cluster is dropped. Ties go to the lower cluster index.
// Bounds: iterations * m * k distance evaluations.
#pragma once

#include "geojcbb/cluster/groups.hpp"
#include "geojcbb/core/grouping_options.hpp"

namespace geojcbb {

struct KMeansStats {
  int iterations = 0;
  bool converged = false;
};

/// @param k  clusters requested, 1 .. MaxGroups (fewer result when there are fewer distinct points)
template <typename T, class B>
KMeansStats kmeans(const Points<T, B>& pts, int m, int k, int max_iterations, Groups<B>& out) {
  KMeansStats st;
  std::array<Vec2<T>, B::kMaxGroups> c;
  int kc = farthest_first<T, B>(pts, m, k, c);
  for (int i = 0; i < m; ++i) out.label[i] = -1;           // <= kMaxObservations
  for (int it = 0; it < max_iterations && kc > 0; ++it) {  // <= kMaxKMeansIterations
    st.iterations = it + 1;
    bool changed = false;
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      int arg = 0;
      T best = (pts[i] - c[0]).squaredNorm();
      for (int q = 1; q < kc; ++q) {  // <= kMaxGroups
        const T d = (pts[i] - c[q]).squaredNorm();
        if (d < best) {
          best = d;
          arg = q;
        }
      }
      changed = changed || out.label[i] != arg;
      out.label[i] = static_cast<std::int8_t>(arg);
    }
    if (!changed) {
      st.converged = true;
      break;
    }
    std::array<int, B::kMaxGroups> n{};
    std::array<Vec2<T>, B::kMaxGroups> sum;
    for (int q = 0; q < kc; ++q) sum[q].setZero();  // <= kMaxGroups
    for (int i = 0; i < m; ++i) {                   // <= kMaxObservations
      sum[out.label[i]] += pts[i];
      ++n[out.label[i]];
    }
    int kept = 0;                   // drop emptied clusters; labels are recomputed next iteration
    for (int q = 0; q < kc; ++q) {  // <= kMaxGroups
      if (n[q] > 0) c[kept++] = sum[q] / static_cast<T>(n[q]);
    }
    kc = kept;
  }
  compact_labels(m, out);
  return st;
}

}  // namespace geojcbb
