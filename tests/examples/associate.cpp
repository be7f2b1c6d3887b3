// README.md's "Using the library" example, as a program CTest builds and runs (docs.examples_current
// keeps the README's block equal to the lines between the doc markers). One observation of one
// candidate: GEOJCBB pairs them.
#include <cstdio>

// [doc]
#include "geojcbb/associate.hpp"
using namespace geojcbb;
using B = DefaultBounds;                   // 24 observations, 32 candidates, 4000 JCBB nodes
static Observations<float, B> obs;         // z_i = (range, bearing), R_i
static Prediction<float, B> pred;          // ids, h_j, C = H P H^T (stored as its lower 2x2 blocks)
static AssociationWorkspace<float, B> ws;  // all working memory
static Association<float, B> out;
static AssociationConfig<float, B> cfg;  // or set every switch by hand

int associate_one_scan() {
  StepSettings<float> settings;    // every option at its default (docs/options.md)
  settings.local_radius_m = 12.f;  // r + d (eq. 5)
  if (make_strategy(Strategy::kGeojcbb, settings, cfg) != Status::kOk) return 1;
  Status s = obs.push(Vec2<float>(5.f, 0.1f), Mat2<float>(Vec2<float>(0.01f, 1e-4f).asDiagonal()));
  if (s != Status::kOk) return 1;
  pred.count = 1;  // candidate 0: map feature 7, predicted at (5.05 m, 0.1 rad)
  pred.id[0] = 7;
  pred.h[0] = Vec2<float>(5.05f, 0.1f);
  if (pred.C.resize(1) != Status::kOk) return 1;
  pred.C.set_block(0, 0, Mat2<float>(Vec2<float>(0.02f, 2e-4f).asDiagonal()));  // C_00 (and C_ab, a >= b)
  s = associate(obs, pred, cfg, ws, out);                                       // out untouched unless s == Status::kOk
  if (s != Status::kOk) return 1;
  // out.feature[i]: a feature id, kNewFeature (nothing compatible) or kUnmatched (ambiguous)
  return out.feature[0] == 7 ? 0 : 1;
}
// [/doc]

int main() {
  const int rc = associate_one_scan();
  std::printf("associate: observation 0 -> feature %d\n", static_cast<int>(out.feature[0]));
  return rc;
}
