// The C++ side of the C API test: the same calls made through the C++ API (associate_f32 and
// node::SlamStep<float, DefaultBounds>), so test_c_api.c can compare the answers bit for bit.
#include <cstring>

#include "geojcbb.h"
#include "geojcbb/c_settings.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "geojcbb/pipeline_f32.hpp"

using namespace geojcbb;
using B = DefaultBounds;

namespace {
ObservationsF g_obs;
PredictionF g_pred;
AssociationWorkspaceF g_ws;
AssociationF g_out;
node::SlamStep<float, B> g_step;
node::StepResult<float, B> g_res;

void load(int m, const float* z, const float* R) {
  g_obs.count = m;
  for (int i = 0; i < m; ++i) {
    g_obs.z[i] = Vec2<float>(z[2 * i], z[2 * i + 1]);
    g_obs.R[i] << R[4 * i], R[4 * i + 1], R[4 * i + 2], R[4 * i + 3];
  }
}
}  // namespace

extern "C" int ref_associate(const geojcbb_settings* p, int m, const float* z, const float* R, int n,
                             const int32_t* ids, const float* h, const float* C, int32_t* feature, float* d2,
                             float* joint_d2, int* pairings, uint32_t* nodes) {
  AssociationConfigF cfg;
  // The product's own C boundary (geojcbb/c_settings.hpp), then the C++ pipeline.
  const StepSettings<float> settings = c_boundary::from_c(*p);
  Status s = make_strategy(settings.strategy, settings, cfg);
  if (s != Status::kOk) return static_cast<int>(s);
  load(m, z, R);
  s = g_pred.C.assign_dense(
      Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(C, 2 * n, 2 * n));
  if (s != Status::kOk) return static_cast<int>(s);
  g_pred.count = n;
  for (int j = 0; j < n; ++j) {
    g_pred.id[j] = ids[j];
    g_pred.h[j] = Vec2<float>(h[2 * j], h[2 * j + 1]);
  }
  s = associate_f32(g_obs, g_pred, cfg, g_ws, g_out);
  if (s != Status::kOk) return static_cast<int>(s);
  for (int i = 0; i < m; ++i) {
    feature[i] = g_out.feature[i];
    d2[i] = g_out.d2[i];
  }
  *joint_d2 = g_out.joint_d2;
  *pairings = g_out.pairings;
  *nodes = g_out.diag.jcbb_nodes;
  return 0;
}

extern "C" int ref_slam_start(const geojcbb_settings* settings, const float x0[3], const float P0[9]) {
  const node::StepSettings<float> st = c_boundary::from_c(*settings);
  Status s = g_step.configure(st);
  if (s != Status::kOk) return static_cast<int>(s);
  Mat3<float> P;
  P << P0[0], P0[1], P0[2], P0[3], P0[4], P0[5], P0[6], P0[7], P0[8];
  return static_cast<int>(g_step.reset(Pose2<float>{x0[0], x0[1], x0[2]}, P));
}

extern "C" int ref_slam_predict(float v, float w, float dt, float sv, float sw) {
  return static_cast<int>(g_step.predict(ekf::Odometry<float>{v, w, dt, sv, sw}));
}

extern "C" int ref_slam_step(int m, const float* z, const float* R, int32_t* feature, uint8_t* outcome, float pose[3]) {
  load(m, z, R);
  const Status s = g_step.step(g_obs, g_res);
  if (s != Status::kOk) return static_cast<int>(s);
  for (int i = 0; i < m; ++i) {
    feature[i] = g_res.feature[i];
    outcome[i] = static_cast<uint8_t>(g_res.outcome[i]);
  }
  const Pose2<float> x = g_step.slam().pose();
  pose[0] = x.x;
  pose[1] = x.y;
  pose[2] = x.theta;
  return 0;
}
