// cluster: the grouping stage (ARCHITECTURE.md step 3b): the observations' points, split by the
// method the configuration names (none | k-means | DBSCAN | GMM-EM). Input: the observations and the
// association's configuration (it reads grouping, groups, kmeans_max_iterations, dbscan_eps_m,
// dbscan_min_points and em). Output: a group label per observation.
// Bounds: those of the chosen method (kmeans.hpp, dbscan.hpp, gmm_em.hpp).
#pragma once

#include <cstdint>

#include "geojcbb/cluster/dbscan.hpp"
#include "geojcbb/cluster/gmm_em.hpp"
#include "geojcbb/cluster/groups.hpp"
#include "geojcbb/cluster/kmeans.hpp"
#include "geojcbb/core/association_config.hpp"

namespace geojcbb {

/// The grouping stage's working memory.
template <typename T, class B>
struct GroupingWorkspace {
  Points<T, B> points;
  EmWorkspace<T, B> em;
};

struct GroupingStats {
  int iterations = 0;      ///< k-means or EM iterations (EM: over every BIC fit)
  bool bound_hit = false;  ///< stopped at the iteration bound, or DBSCAN merged groups for capacity
};

/// Splits the observations into groups (one group without grouping; none for no observations).
template <typename T, class B>
GroupingStats group_observations(const Observations<T, B>& obs, const AssociationConfig<T, B>& opt,
                                 GroupingWorkspace<T, B>& ws, Groups<B>& g) {
  GroupingStats st;
  const int m = obs.count;
  if (opt.grouping == Grouping::kNone || m == 0) {
    for (int i = 0; i < m; ++i) g.label[i] = 0;  // <= kMaxObservations
    g.count = m > 0 ? 1 : 0;
    return st;
  }
  observation_points(obs, ws.points);
  if (opt.grouping == Grouping::kKMeans) {
    const KMeansStats k = kmeans(ws.points, m, opt.groups, opt.kmeans_max_iterations, g);
    st.iterations = k.iterations;
    st.bound_hit = !k.converged;
  } else if (opt.grouping == Grouping::kDbscan) {
    const DbscanStats d = dbscan(ws.points, m, opt.dbscan_eps_m, opt.dbscan_min_points, g);
    st.bound_hit = d.merged_for_capacity;
  } else {
    const EmStats<T> e = gmm_em(ws.points, m, opt.groups, opt.em, ws.em, g);
    st.iterations = e.total_iterations;
    st.bound_hit = !e.converged;
  }
  return st;
}

}  // namespace geojcbb
