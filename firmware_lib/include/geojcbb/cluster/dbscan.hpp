// cluster: DBSCAN (DFJCBB's grouping, Ester et al. 1996) over the observations' points.
// A point is a core point when at least min_points points (itself included) lie within eps. Clusters
// grow from core points through an explicit queue (no recursion). A border point joins the first
// cluster that reaches it. Noise points become singleton groups: clustering never drops an
// observation. When the groups outnumber MaxGroups, the surplus groups (the latest formed) are
// merged into the last one (JCBB over a merged group is still exact, only larger).
// Bounds: m^2 distance evaluations; each point enters the queue at most once.
#pragma once

#include "geojcbb/cluster/groups.hpp"

namespace geojcbb {

struct DbscanStats {
  int clusters = 0;                  ///< density clusters found
  int noise = 0;                     ///< noise points (each its own group)
  bool merged_for_capacity = false;  ///< groups beyond MaxGroups were merged into the last
};

template <typename T, class B>
DbscanStats dbscan(const Points<T, B>& pts, int m, T eps, int min_points, Groups<B>& out) {
  DbscanStats st;
  const T eps2 = eps * eps;
  std::array<std::int8_t, B::kMaxObservations> neighbours{};
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    int n = 0;
    for (int j = 0; j < m; ++j) n += (pts[i] - pts[j]).squaredNorm() <= eps2;  // <= kMaxObservations
    neighbours[i] = static_cast<std::int8_t>(n);
  }
  std::array<int, B::kMaxObservations> raw;  // cluster per point, -1 unvisited/noise
  raw.fill(-1);
  std::array<std::uint8_t, B::kMaxObservations> queue;  ///< observation indices
  int clusters = 0;
  for (int s = 0; s < m; ++s) {  // <= kMaxObservations
    if (raw[s] >= 0 || neighbours[s] < min_points) continue;
    const int c = clusters++;
    int head = 0, tail = 0;
    raw[s] = c;
    queue[tail++] = static_cast<std::uint8_t>(s);
    while (head < tail) {  // each point is queued at most once: <= kMaxObservations
      const int p = queue[head++];
      if (neighbours[p] < min_points) continue;  // border point: does not expand
      for (int q = 0; q < m; ++q) {              // <= kMaxObservations
        if (raw[q] < 0 && (pts[p] - pts[q]).squaredNorm() <= eps2) {
          raw[q] = c;
          queue[tail++] = static_cast<std::uint8_t>(q);
        }
      }
    }
  }
  st.clusters = clusters;
  int next = clusters;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (raw[i] < 0) {
      raw[i] = next++;
      ++st.noise;
    }
  }
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    int g = raw[i];
    if (g >= B::kMaxGroups) {
      g = B::kMaxGroups - 1;
      st.merged_for_capacity = true;
    }
    out.label[i] = static_cast<std::int8_t>(g);
  }
  compact_labels(m, out);
  return st;
}

}  // namespace geojcbb
