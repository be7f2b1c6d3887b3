// cluster: what every clustering stage produces: a group label per observation, and the points it
// clusters. Points are the observations' Cartesian positions in the sensor frame. The papers cluster
// in the world frame (through the predicted pose). k-means, DBSCAN and GMM-EM (isotropic floor,
// farthest-first start) are invariant to a rigid transform, so the groups are the same, and the
// association core needs no pose.
// Bounds: MaxObservations points, MaxGroups groups.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geojcbb/core/association_types.hpp"

namespace geojcbb {

template <class B>
struct Groups {
  int count = 0;                                       ///< groups, 1 .. MaxGroups (0 for no points)
  std::array<std::int8_t, B::kMaxObservations> label;  ///< observation -> group, 0 .. count - 1
};

template <typename T, class B>
using Points = std::array<Vec2<T>, B::kMaxObservations>;

/// Sensor-frame Cartesian points of the observations.  Bound: m <= MaxObservations.
template <typename T, class B>
void observation_points(const Observations<T, B>& obs, Points<T, B>& pts) {
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    pts[i] = Vec2<T>(obs.z[i].x() * fmath::cos(obs.z[i].y()), obs.z[i].x() * fmath::sin(obs.z[i].y()));
  }
}

/// Deterministic, rigid-invariant seeds: the point farthest from the centroid, then repeatedly the
/// point farthest from its nearest seed (ties: lowest index). Returns the seed count (<= k, fewer
/// when the points have fewer distinct positions).  Bound: k * m distance evaluations.
template <typename T, class B>
int farthest_first(const Points<T, B>& pts, int m, int k, std::array<Vec2<T>, B::kMaxGroups>& seeds) {
  if (m == 0 || k == 0) return 0;
  Vec2<T> centroid = Vec2<T>::Zero();
  for (int i = 0; i < m; ++i) centroid += pts[i];  // <= kMaxObservations
  centroid /= static_cast<T>(m);
  std::array<T, B::kMaxObservations> nearest;
  for (int i = 0; i < m; ++i) nearest[i] = (pts[i] - centroid).squaredNorm();  // <= kMaxObservations
  int n = 0;
  for (; n < k; ++n) {  // <= kMaxGroups
    int arg = 0;
    for (int i = 1; i < m; ++i) {  // <= kMaxObservations
      if (nearest[i] > nearest[arg]) arg = i;
    }
    if (n > 0 && !(nearest[arg] > T(0))) break;  // every point coincides with a seed
    seeds[n] = pts[arg];
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      const T d = (pts[i] - seeds[n]).squaredNorm();
      if (n == 0 || d < nearest[i]) nearest[i] = d;
    }
  }
  return n;
}

/// Renumbers labels to 0 .. groups - 1 in order of first appearance, dropping empty groups.
/// Bound: m <= MaxObservations, labels < MaxObservations.
template <class B>
void compact_labels(int m, Groups<B>& g) {
  std::array<std::int8_t, B::kMaxObservations> map;
  map.fill(-1);
  int n = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    std::int8_t& to = map[g.label[i]];
    if (to < 0) to = static_cast<std::int8_t>(n++);
    g.label[i] = to;
  }
  g.count = n;
}

}  // namespace geojcbb
