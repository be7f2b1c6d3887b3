// Associates one observation with one candidate through the installed headers.
#include "geojcbb/associate.hpp"

using namespace geojcbb;
using B = DefaultBounds;

int main() {
  static Observations<float, B> obs;
  static Prediction<float, B> pred;
  static AssociationWorkspace<float, B> ws;
  static Association<float, B> out;
  AssociationConfig<float, B> cfg;
  if (GateThresholds<float, B::kMaxObservations>::from_confidence(0.99, 0.99, cfg.gate) != Status::kOk) return 1;
  if (obs.push(Vec2<float>(5.f, 0.1f), Mat2<float>::Identity() * 0.01f) != Status::kOk) return 1;
  pred.count = 1;
  pred.id[0] = 7;
  pred.h[0] = Vec2<float>(5.05f, 0.1f);
  pred.C.set_identity(1, 0.02f);
  if (associate(obs, pred, cfg, ws, out) != Status::kOk) return 1;
  return out.feature[0] == 7 ? 0 : 1;
}
