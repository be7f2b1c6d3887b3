/* core: what one association call reports about itself (AssociationDiagnostics), described once.
 * C++, C, Python and the tools read this table (an X-macro, as core/options.h): the C++ struct
 * (core/association_types.hpp), the C struct geojcbb_diagnostics and its conversion (geojcbb.h,
 * c_api.cpp), Python's `diag` dict, and the docs. A new diagnostic is one line here and the stage
 * that counts it.
 *
 * X(TYPE, name, meaning)
 *   TYPE  U32 (uint32_t), U16 (uint16_t), U8 (uint8_t), BOOL (bool; uint8_t 0/1 in C) */
#ifndef GEOJCBB_CORE_DIAGNOSTICS_H
#define GEOJCBB_CORE_DIAGNOSTICS_H

/* clang-format off */
#define GEOJCBB_DIAGNOSTICS(X) \
  X(U32, jcbb_nodes, "interpretation-tree nodes expanded") \
  X(U16, candidates_in_region, "candidates left after the local region (eq. 5)") \
  X(U16, compatible_pairs, "(observation, candidate) pairs passing the individual gate") \
  X(BOOL, node_budget_hit, "JCBB stopped at its node budget: the best so far was returned") \
  X(U8, groups, "observation groups searched") \
  X(U16, cluster_iterations, "k-means or EM iterations (EM: over every BIC fit)") \
  X(BOOL, cluster_bound_hit, \
    "the clustering stopped at its iteration bound before converging, or DBSCAN merged groups beyond MaxGroups") \
  X(U16, merge_conflicts, "features claimed by two groups (mutual exclusion)") \
  X(BOOL, recheck_failed, "the merged union failed the joint test and was repaired") \
  X(U16, recheck_dropped, "pairings the repair removed") \
  X(U16, declined, "pairings left unmatched as ambiguous (ambiguity_margin)") \
  X(U16, verify_dropped, "pairings the verification dropped (not pairwise consistent)") \
  X(BOOL, seed_tried, "the pose was uncertain: the pose-free clique was computed") \
  X(BOOL, seed_used, "the clique passed the joint test and seeded the search") \
  X(U16, seed_pairings, "pairings of the clique (when tried)") \
  X(U16, clique_graph_nodes, "graph nodes of the last consistency graph (seed or verify)") \
  X(U32, clique_search_nodes, "max-clique search nodes, seed and verify together") \
  X(BOOL, clique_budget_hit, "a max-clique search stopped at its budget (the best so far was used)") \
  X(BOOL, clique_nodes_truncated, "the seed's wide gate passed more pairings than the graph holds nodes") \
  X(BOOL, rjc_used, "the scan was searched by RJC (rjc on and a large scan)")
/* clang-format on */

#endif /* GEOJCBB_CORE_DIAGNOSTICS_H */
