// The C API (geojcbb.h) over the float pipeline and the SLAM step at DefaultBounds. The objects are
// placed in the caller's storage with placement new (no heap); every C mirror of a C++ enum or
// capacity is checked against it here, as are the storage sizes the header publishes.
#include "geojcbb.h"

#include <cstring>
#include <new>

#include "geojcbb/c_settings.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "geojcbb/pipeline_f32.hpp"

namespace {

using namespace geojcbb;
using B = DefaultBounds;

static_assert(GEOJCBB_MAX_OBSERVATIONS == B::kMaxObservations && GEOJCBB_MAX_CANDIDATES == B::kMaxCandidates &&
                  GEOJCBB_MAX_GROUPS == B::kMaxGroups && GEOJCBB_MAX_JCBB_NODES == B::kMaxJcbbNodes &&
                  GEOJCBB_MAX_LANDMARKS == B::kMaxLandmarks,
              "geojcbb.h capacities differ from DefaultBounds");
static_assert(GEOJCBB_NEW_FEATURE == kNewFeature && GEOJCBB_UNMATCHED == kUnmatched, "feature codes");

#define GEOJCBB_SAME(c, cpp) static_assert(static_cast<int>(c) == static_cast<int>(cpp), #c " != " #cpp)
GEOJCBB_SAME(GEOJCBB_OK, Status::kOk);
GEOJCBB_SAME(GEOJCBB_NON_FINITE, Status::kNonFinite);
GEOJCBB_SAME(GEOJCBB_INVALID_INPUT, Status::kInvalidInput);
GEOJCBB_SAME(GEOJCBB_CAPACITY_EXCEEDED, Status::kCapacityExceeded);
GEOJCBB_SAME(GEOJCBB_NOT_SYMMETRIC, Status::kNotSymmetric);
GEOJCBB_SAME(GEOJCBB_NOT_POSITIVE_DEFINITE, Status::kNotPositiveDefinite);
GEOJCBB_SAME(GEOJCBB_NO_CONVERGENCE, Status::kNoConvergence);
// The last C status is the last C++ one: a new Status value must be added to geojcbb.h.
static_assert(to_string(static_cast<Status>(GEOJCBB_NO_CONVERGENCE + 1))[0] == 'u', "a Status missing in geojcbb.h");
GEOJCBB_SAME(GEOJCBB_STRATEGY_ICNN, Strategy::kIcnn);
GEOJCBB_SAME(GEOJCBB_STRATEGY_JCBB, Strategy::kJcbb);
GEOJCBB_SAME(GEOJCBB_STRATEGY_KJCBB, Strategy::kKjcbb);
GEOJCBB_SAME(GEOJCBB_STRATEGY_DFJCBB, Strategy::kDfjcbb);
GEOJCBB_SAME(GEOJCBB_STRATEGY_GEMJCBB, Strategy::kGemjcbb);
GEOJCBB_SAME(GEOJCBB_STRATEGY_GEOJCBB, Strategy::kGeojcbb);
GEOJCBB_SAME(GEOJCBB_STRATEGY_PCJCBB, Strategy::kPcjcbb);
GEOJCBB_SAME(GEOJCBB_STRATEGY_PCJCBB, Strategy::kPcjcbb);
static_assert(GEOJCBB_STRATEGY_PCJCBB + 1 == kStrategyCount, "a Strategy missing in geojcbb.h");
GEOJCBB_SAME(GEOJCBB_OUTCOME_PAIRED, node::Outcome::kPaired);
GEOJCBB_SAME(GEOJCBB_OUTCOME_NEW_LANDMARK, node::Outcome::kNewLandmark);
GEOJCBB_SAME(GEOJCBB_OUTCOME_NEW_DROPPED, node::Outcome::kNewDropped);
GEOJCBB_SAME(GEOJCBB_OUTCOME_UNMATCHED, node::Outcome::kUnmatched);
GEOJCBB_SAME(GEOJCBB_OUTCOME_NOT_AUGMENTED, node::Outcome::kNotAugmented);
GEOJCBB_SAME(GEOJCBB_OUTCOME_MOVER, node::Outcome::kMover);
#undef GEOJCBB_SAME

constexpr std::uint32_t kAssociatorMagic = 0x6A636231u;  // "jcb1"
constexpr std::uint32_t kSlamMagic = 0x736C6D31u;        // "slm1"

struct Associator {
  std::uint32_t magic = kAssociatorMagic;
  AssociationConfigF cfg;
  ObservationsF obs;
  PredictionF pred;
  AssociationWorkspaceF ws;
  AssociationF out;
  StepSettings<float> settings;  ///< the C settings, converted (init's scratch)
};

struct Slam {
  std::uint32_t magic = kSlamMagic;
  node::SlamStep<float, B> step;
  ObservationsF obs;
  node::StepResult<float, B> res;
  // configure()'s settings are built here, not on the stack: with make_strategy inlined below it, a
  // local copy took geojcbb_slam_configure's frame to 552 B on the Cortex-M4F (limit 512).
  node::StepSettings<float> settings;
};

// The header's sizes are exact, so a change of layout (new capacity, new workspace member) shows
// here first: update GEOJCBB_*_STORAGE_SIZE in geojcbb.h to the size in the message.
template <std::size_t Have, std::size_t Want>
constexpr bool storage_size_matches() {
  static_assert(Have == Want, "geojcbb.h: GEOJCBB_*_STORAGE_SIZE differs from sizeof (see the template arguments)");
  return true;
}
static_assert(storage_size_matches<GEOJCBB_ASSOCIATOR_STORAGE_SIZE, sizeof(Associator)>());
static_assert(storage_size_matches<GEOJCBB_SLAM_STORAGE_SIZE, sizeof(Slam)>());
static_assert(GEOJCBB_STORAGE_ALIGN == alignof(Associator) && GEOJCBB_STORAGE_ALIGN == alignof(Slam),
              "geojcbb.h: GEOJCBB_STORAGE_ALIGN differs from alignof");

geojcbb_status c_status(Status s) { return static_cast<geojcbb_status>(s); }

bool storage_ok(const void* p, std::size_t size, std::size_t need) {
  return p != nullptr && size >= need && reinterpret_cast<std::uintptr_t>(p) % GEOJCBB_STORAGE_ALIGN == 0;
}

bool strategy_ok(int s) { return s >= 0 && s < kStrategyCount; }

/// Generated from core/diagnostics.h: every diagnostic, a bool as 0/1.
geojcbb_diagnostics to_c(const AssociationDiagnostics& d) {
  geojcbb_diagnostics c;
#define GEOJCBB_DIAG_TO_C(TYPE, name, doc) c.name = options::convert<decltype(c.name)>(d.name);
  GEOJCBB_DIAGNOSTICS(GEOJCBB_DIAG_TO_C)
#undef GEOJCBB_DIAG_TO_C
  return c;
}

/// Copies m observations into obs. @return kOk; kInvalidInput (null arrays, m < 0);
/// kCapacityExceeded. Values are validated by associate().
Status load_observations(int m, const float* z, const float* R, ObservationsF& obs) {
  if (m < 0 || (m > 0 && (z == nullptr || R == nullptr))) return Status::kInvalidInput;
  if (m > B::kMaxObservations) return Status::kCapacityExceeded;
  obs.count = m;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    obs.z[i] = Vec2<float>(z[2 * i], z[2 * i + 1]);
    obs.R[i] << R[4 * i], R[4 * i + 1], R[4 * i + 2], R[4 * i + 3];
  }
  return Status::kOk;
}

/// The caller's row-major dense C (dim x dim floats), as BlockCovariance::assign_dense reads it.
struct RowMajorView {
  const float* C;
  int dim;
  int rows() const { return dim; }
  int cols() const { return dim; }
  float operator()(int r, int c) const {
    return C[static_cast<std::size_t>(r) * static_cast<std::size_t>(dim) + static_cast<std::size_t>(c)];
  }
};

}  // namespace

extern "C" {

const char* geojcbb_status_name(geojcbb_status s) { return to_string(static_cast<Status>(s)); }

void geojcbb_settings_default(geojcbb_settings* s) {
  if (s != nullptr) *s = c_boundary::to_c(StepSettings<float>{});
}

geojcbb_status geojcbb_associator_init(void* storage, size_t size, const geojcbb_settings* settings,
                                       geojcbb_associator** out) {
  if (!storage_ok(storage, size, sizeof(Associator)) || settings == nullptr || out == nullptr ||
      !strategy_ok(static_cast<int>(settings->strategy))) {
    return GEOJCBB_INVALID_INPUT;
  }
  // Built in the storage, not on the stack: a local AssociationConfig (it holds the settings) took
  // this frame to 648 B on the Cortex-M4F (limit 512). Refused settings leave an unusable object.
  Associator* a = new (storage) Associator();
  a->settings = c_boundary::from_c(*settings);
  const Status s = make_strategy(static_cast<Strategy>(settings->strategy), a->settings, a->cfg);
  if (s != Status::kOk) {
    a->magic = 0;
    return c_status(s);
  }
  *out = reinterpret_cast<geojcbb_associator*>(a);
  return GEOJCBB_OK;
}

geojcbb_status geojcbb_associate(geojcbb_associator* handle, int m, const float* z, const float* R, int n,
                                 const int32_t* ids, const float* h, const float* C, geojcbb_association* out) {
  Associator* a = reinterpret_cast<Associator*>(handle);
  if (a == nullptr || a->magic != kAssociatorMagic || out == nullptr || n < 0 ||
      (n > 0 && (ids == nullptr || h == nullptr || C == nullptr))) {
    return GEOJCBB_INVALID_INPUT;
  }
  if (n > B::kMaxCandidates) return GEOJCBB_CAPACITY_EXCEEDED;
  Status s = load_observations(m, z, R, a->obs);
  if (s != Status::kOk) return c_status(s);
  PredictionF& p = a->pred;
  // The caller's C is dense (row-major 2n x 2n); the prediction holds its lower block triangle, so an
  // asymmetric cross block is rejected here (GEOJCBB_NOT_SYMMETRIC) rather than where it is read.
  s = p.C.assign_dense(RowMajorView{C, 2 * n});
  if (s != Status::kOk) return c_status(s);
  p.count = n;
  for (int j = 0; j < n; ++j) {  // <= kMaxCandidates
    p.id[j] = ids[j];
    p.h[j] = Vec2<float>(h[2 * j], h[2 * j + 1]);
  }
  s = associate_f32(a->obs, p, a->cfg, a->ws, a->out);
  if (s != Status::kOk) return c_status(s);
  const AssociationF& o = a->out;
  out->count = o.count;
  for (int i = 0; i < o.count; ++i) {  // <= kMaxObservations
    out->feature[i] = o.feature[i];
    out->candidate[i] = o.candidate[i];
    out->d2[i] = o.d2[i];
  }
  out->pairings = o.pairings;
  out->joint_d2 = o.joint_d2;
  out->jointly_compatible = o.jointly_compatible ? 1 : 0;
  out->diag = to_c(o.diag);
  return GEOJCBB_OK;
}

geojcbb_status geojcbb_slam_init(void* storage, size_t size, geojcbb_slam** out) {
  if (!storage_ok(storage, size, sizeof(Slam)) || out == nullptr) return GEOJCBB_INVALID_INPUT;
  *out = reinterpret_cast<geojcbb_slam*>(new (storage) Slam());
  return GEOJCBB_OK;
}

static Slam* slam_of(geojcbb_slam* handle) {
  Slam* s = reinterpret_cast<Slam*>(handle);
  return s != nullptr && s->magic == kSlamMagic ? s : nullptr;
}

geojcbb_status geojcbb_slam_configure(geojcbb_slam* handle, const geojcbb_settings* settings) {
  Slam* s = slam_of(handle);
  if (s == nullptr || settings == nullptr || !strategy_ok(static_cast<int>(settings->strategy)))
    return GEOJCBB_INVALID_INPUT;
  c_boundary::from_c(*settings, s->settings);
  return c_status(s->step.configure(s->settings));
}

geojcbb_status geojcbb_slam_reset(geojcbb_slam* handle, const float x0[3], const float P0[9]) {
  Slam* s = slam_of(handle);
  if (s == nullptr || x0 == nullptr || P0 == nullptr) return GEOJCBB_INVALID_INPUT;
  Mat3<float> P;
  P << P0[0], P0[1], P0[2], P0[3], P0[4], P0[5], P0[6], P0[7], P0[8];
  return c_status(s->step.reset(Pose2<float>{x0[0], x0[1], x0[2]}, P));
}

geojcbb_status geojcbb_slam_predict(geojcbb_slam* handle, float v_mps, float w_radps, float dt_s, float sigma_v_mps,
                                    float sigma_w_radps) {
  Slam* s = slam_of(handle);
  if (s == nullptr) return GEOJCBB_INVALID_INPUT;
  return c_status(s->step.predict(ekf::Odometry<float>{v_mps, w_radps, dt_s, sigma_v_mps, sigma_w_radps}));
}

geojcbb_status geojcbb_slam_step(geojcbb_slam* handle, int m, const float* z, const float* R,
                                 geojcbb_step_result* out) {
  Slam* s = slam_of(handle);
  if (s == nullptr || out == nullptr) return GEOJCBB_INVALID_INPUT;
  Status st = load_observations(m, z, R, s->obs);
  if (st != Status::kOk) return c_status(st);
  st = s->step.step(s->obs, s->res);
  if (st != Status::kOk) return c_status(st);
  out->count = s->res.count;
  for (int i = 0; i < s->res.count; ++i) {  // <= kMaxObservations
    out->outcome[i] = static_cast<std::uint8_t>(s->res.outcome[i]);
    out->feature[i] = s->res.feature[i];
    out->d2[i] = s->res.d2[i];
  }
  out->diag = to_c(s->res.diag);
  return GEOJCBB_OK;
}

void geojcbb_slam_pose(const geojcbb_slam* handle, float x[3]) {
  const Slam* s = reinterpret_cast<const Slam*>(handle);
  if (s == nullptr || x == nullptr || s->magic != kSlamMagic) return;
  const Pose2<float> p = s->step.slam().pose();
  x[0] = p.x;
  x[1] = p.y;
  x[2] = p.theta;
}

int geojcbb_slam_landmarks(const geojcbb_slam* handle) {
  const Slam* s = reinterpret_cast<const Slam*>(handle);
  return s != nullptr && s->magic == kSlamMagic ? s->step.slam().landmarks() : 0;
}

geojcbb_status geojcbb_slam_landmark(const geojcbb_slam* handle, int j, int32_t* id, float xy[2]) {
  const Slam* s = reinterpret_cast<const Slam*>(handle);
  if (s == nullptr || s->magic != kSlamMagic || id == nullptr || xy == nullptr || j < 0 ||
      j >= s->step.slam().landmarks()) {
    return GEOJCBB_INVALID_INPUT;
  }
  *id = s->step.slam().id(j);
  const Vec2<float> l = s->step.slam().landmark(j);
  xy[0] = l.x();
  xy[1] = l.y();
  return GEOJCBB_OK;
}

}  // extern "C"
