// The association pipeline: the only file that knows the order of the stages.
//   validate -> local region + individual gate -> search (ICNN | JCBB) -> result
// (Grouping and the merge of the grouped strategies arrive in issue 3, between gate and result.)
// No heap: all working memory is the caller's Workspace; outputs are written only on kOk.
#pragma once

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/gate/validate.hpp"
#include "geojcbb/jcbb/icnn.hpp"
#include "geojcbb/jcbb/jcbb.hpp"

namespace geojcbb {

/// Caller-owned working memory of associate(); typically a static object on the device.
template <typename T, class B>
struct Workspace {
  CompatibilityTable<T, B> table;
  JcbbWorkspace<T, B> jcbb;
  SearchOutcome<T, B> outcome;
};

/// Associates one scan's observations with the predicted candidates.
/// @param[in]  obs   observations (range, bearing) and their noise
/// @param[in]  pred  candidate ids, predicted measurements h and their joint covariance C
/// @param[in]  cfg   options (see AssociationConfig)
/// @param[in,out] ws working memory
/// @param[out] out   the hypothesis; written only when kOk is returned
/// @return kOk (an empty scan gives an empty answer; a spent node budget is flagged in
///         out.diag.node_budget_hit); otherwise the first failing check of validate(), or
///         kNotPositiveDefinite when C is found indefinite during the joint test.
template <typename T, class B>
[[nodiscard]] Status associate(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                               const AssociationConfig<T, B>& cfg, Workspace<T, B>& ws,
                               Association<T, B>& out) {
  Status s = validate(obs, pred, cfg);
  if (s != Status::kOk) return s;
  AssociationDiagnostics diag{};
  build_compatibility(obs, pred, cfg, ws.table, diag);
  SearchOutcome<T, B>& o = ws.outcome;
  if (cfg.search == SearchMethod::kIcnn) {
    icnn_search(obs.count, cfg.mutual_exclusion, ws.table, ws.jcbb, pred.count, o);
    s = hypothesis_joint_d2(obs, pred, o.best, ws.jcbb.joint, o.joint_d2);
  } else {
    s = jcbb_search(obs, pred, cfg, ws.table, ws.jcbb, o);
  }
  if (s != Status::kOk) return s;

  out.count = obs.count;
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    const int c = o.best[i];
    out.candidate[i] = static_cast<std::int16_t>(c);
    if (c >= 0) {
      out.feature[i] = pred.id[c];
      const Mat2<T> S = pred.C.template block<2, 2>(2 * c, 2 * c) + obs.R[i];
      out.d2[i] = mahalanobis2(innovation(obs.z[i], pred.h[c]), S);
    } else {
      out.feature[i] = ws.table.count[i] == 0 ? kNewFeature : kUnmatched;
      out.d2[i] = ws.table.nearest_d2[i];
    }
  }
  out.pairings = o.pairings;
  out.joint_d2 = o.joint_d2;
  out.jointly_compatible = o.joint_d2 <= cfg.gate.joint[o.pairings];
  diag.jcbb_nodes = o.nodes;
  diag.node_budget_hit = o.budget_hit;
  out.diag = diag;
  return Status::kOk;
}

}  // namespace geojcbb
