// Python bindings (pybind11) of the association pipeline, the EKF-SLAM step and the simulator, in
// double at host bounds (PyBounds below; docs/python.md). Arrays are read straight from the NumPy
// buffers (C-contiguous float64 is used as is; anything else is converted once by NumPy); every
// Status other than kOk is raised as geojcbb.GeojcbbError with .status set to its name.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "geojcbb/associate.hpp"
#include "geojcbb/core/presets.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "geojcbb_host/sim.hpp"

namespace py = pybind11;
using namespace geojcbb;

/// Host capacities: 64 observations per scan, 128 candidates, 8 groups, 200000 JCBB nodes, 500
/// landmarks (the evaluation's capacities, docs/python.md).
using PyBounds = Bounds<64, 128, 8, 200000, 500>;
using T = double;
using Arr = py::array_t<double, py::array::c_style | py::array::forcecast>;

namespace {

py::object g_error;

const char* status_name(Status s) {
  switch (s) {
    case Status::kOk: return "kOk";
    case Status::kNonFinite: return "kNonFinite";
    case Status::kInvalidInput: return "kInvalidInput";
    case Status::kCapacityExceeded: return "kCapacityExceeded";
    case Status::kNotSymmetric: return "kNotSymmetric";
    case Status::kNotPositiveDefinite: return "kNotPositiveDefinite";
    case Status::kNoConvergence: return "kNoConvergence";
  }
  return "kUnknown";
}

[[noreturn]] void raise(Status s, const std::string& what) {
  py::object e = g_error(what + ": " + to_string(s) + " (" + status_name(s) + ")");
  e.attr("status") = status_name(s);
  PyErr_SetObject(g_error.ptr(), e.ptr());
  throw py::error_already_set();
}
void check(Status s, const char* what) {
  if (s != Status::kOk) raise(s, what);
}

/// The settings from keyword arguments, each named as its option (core/options.h); "strategy" as a
/// preset's name with its suffixes, read by the command-line tools' grammar (core/presets.hpp).
StepSettings<T> parse_settings(const std::string& strategy, const py::kwargs& kw) {
  StepSettings<T> s;
  Preset preset;
  if (!parse_preset(strategy.c_str(), preset)) {
    raise(Status::kInvalidInput, "unknown strategy '" + strategy + "'");
  }
  apply_preset(preset, s);
  for (auto item : kw) {
    const std::string k = py::cast<std::string>(item.first);
    bool known = false;
    for_each_option(s, [&](const options::Info& info, auto& v) {
      using V = std::remove_reference_t<decltype(v)>;
      if (k != info.name) return;
      known = true;
      if constexpr (std::is_same<V, Strategy>::value) {
        throw py::type_error("the strategy is the positional argument 'strategy'");
      } else {
        v = py::cast<V>(item.second);
      }
    });
    if (!known) throw py::type_error("unknown option '" + k + "'");
  }
  return s;
}

/// The options' keywords for the docstrings: "name (TYPE, default d[, unit]): meaning", one a line.
std::string options_doc() {
  std::string d;
  for (const options::Info& o : options::kInfo) {
    if (std::string(o.name) == "strategy") continue;
    d += std::string("  ") + o.name + " (" + o.type + ", default " + o.default_text +
         (o.unit[0] != '\0' ? std::string(", ") + o.unit : std::string()) + "): " + o.meaning + "\n";
  }
  return d;
}

/// z (m, 2), R (m, 2, 2) into obs. Shapes: kInvalidInput; counts: kCapacityExceeded.
void load_observations(const Arr& z, const Arr& R, Observations<T, PyBounds>& obs) {
  if (z.ndim() != 2 || z.shape(1) != 2 || R.ndim() != 3 || R.shape(0) != z.shape(0) || R.shape(1) != 2 ||
      R.shape(2) != 2) {
    raise(Status::kInvalidInput, "z must be (m, 2) and R (m, 2, 2)");
  }
  const py::ssize_t m = z.shape(0);
  if (m > PyBounds::kMaxObservations) raise(Status::kCapacityExceeded, "more observations than 64");
  const double* zp = z.data();
  const double* rp = R.data();
  obs.count = static_cast<int>(m);
  for (py::ssize_t i = 0; i < m; ++i) {
    obs.z[i] = Vec2<T>(zp[2 * i], zp[2 * i + 1]);
    obs.R[i] << rp[4 * i], rp[4 * i + 1], rp[4 * i + 2], rp[4 * i + 3];
  }
}

// Every diagnostic of core/diagnostics.h, by its name.
py::dict diagnostics(const AssociationDiagnostics& d) {
  py::dict o;
  for_each_diagnostic(d, [&o](const char* name, const char*, auto v) { o[name] = v; });
  return o;
}

struct AssocState {
  // The last configuration built: make_strategy computes the chi-square quantiles of every joint
  // test size (2 .. 2 x 64 dof), which costs more than a small association; reused while the
  // strategy and its options stay the same.
  bool have_cfg = false;
  StepSettings<T> settings;
  AssociationConfig<T, PyBounds> cfg;
  Observations<T, PyBounds> obs;
  Prediction<T, PyBounds> pred;
  AssociationWorkspace<T, PyBounds> ws;
  Association<T, PyBounds> out;
};

py::dict associate_py(const Arr& z, const Arr& R, const Arr& h, const Arr& C,
                      const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& ids,
                      const std::string& strategy, const py::kwargs& kw) {
  static std::unique_ptr<AssocState> st(new AssocState());  // several MB: on the heap, reused
  const StepSettings<T> settings = parse_settings(strategy, kw);
  if (!st->have_cfg || !same_settings(settings, st->settings)) {
    st->have_cfg = false;
    check(make_strategy(settings.strategy, settings, st->cfg), "make_strategy");
    st->have_cfg = true;
    st->settings = settings;
  }
  const AssociationConfig<T, PyBounds>& cfg = st->cfg;
  load_observations(z, R, st->obs);
  if (h.ndim() != 2 || h.shape(1) != 2 || ids.ndim() != 1 || ids.shape(0) != h.shape(0) || C.ndim() != 2 ||
      C.shape(0) != 2 * h.shape(0) || C.shape(1) != 2 * h.shape(0)) {
    raise(Status::kInvalidInput, "h must be (n, 2), ids (n,) and C (2n, 2n)");
  }
  const py::ssize_t n = h.shape(0);
  if (n > PyBounds::kMaxCandidates) raise(Status::kCapacityExceeded, "more candidates than 128");
  Prediction<T, PyBounds>& p = st->pred;
  p.count = static_cast<int>(n);
  const double* hp = h.data();
  const std::int64_t* ip = ids.data();
  for (py::ssize_t j = 0; j < n; ++j) {
    if (ip[j] < 0 || ip[j] > 0x7fffffff) raise(Status::kInvalidInput, "ids must be in [0, 2^31)");
    p.id[j] = static_cast<FeatureId>(ip[j]);
    p.h[j] = Vec2<T>(hp[2 * j], hp[2 * j + 1]);
  }
  // Dense in, lower block triangle kept: an asymmetric cross block is rejected here (kNotSymmetric).
  check(p.C.assign_dense(Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            C.data(), 2 * n, 2 * n)),
        "associate");
  check(associate(st->obs, p, cfg, st->ws, st->out), "associate");
  const Association<T, PyBounds>& o = st->out;
  py::array_t<std::int32_t> feature(o.count);
  py::array_t<std::int32_t> candidate(o.count);
  py::array_t<double> d2(o.count);
  for (int i = 0; i < o.count; ++i) {
    feature.mutable_at(i) = o.feature[i];
    candidate.mutable_at(i) = o.candidate[i];
    d2.mutable_at(i) = o.d2[i];
  }
  py::dict r;
  r["feature"] = feature;
  r["candidate"] = candidate;
  r["d2"] = d2;
  r["pairings"] = o.pairings;
  r["joint_d2"] = o.joint_d2;
  r["jointly_compatible"] = o.jointly_compatible;
  r["diagnostics"] = diagnostics(o.diag);
  return r;
}

const char* outcome_name(node::Outcome o) {
  switch (o) {
    case node::Outcome::kPaired: return "paired";
    case node::Outcome::kNewLandmark: return "new_landmark";
    case node::Outcome::kNewDropped: return "new_dropped";
    case node::Outcome::kUnmatched: return "unmatched";
    case node::Outcome::kNotAugmented: return "not_augmented";
    case node::Outcome::kMover: return "mover";
  }
  return "?";
}

/// node::SlamStep<double, PyBounds> with its inputs and outputs (several MB: one heap object).
class PySlam {
 public:
  PySlam(const std::string& strategy, const py::kwargs& kw) : s_(new State()) {
    check(s_->step.configure(parse_settings(strategy, kw)), "configure");
  }
  void reset(const Arr& x0, const Arr& P0) {
    if (x0.size() != 3 || P0.ndim() != 2 || P0.shape(0) != 3 || P0.shape(1) != 3)
      raise(Status::kInvalidInput, "x0 must have 3 values and P0 be (3, 3)");
    const double* p = P0.data();
    Mat3<T> P;
    P << p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8];
    check(s_->step.reset(Pose2<T>{x0.data()[0], x0.data()[1], x0.data()[2]}, P), "reset");
  }
  void predict(double v, double w, double dt, double sv, double sw) {
    check(s_->step.predict(ekf::Odometry<T>{v, w, dt, sv, sw}), "predict");
  }
  py::dict step(const Arr& z, const Arr& R) {
    load_observations(z, R, s_->obs);
    check(s_->step.step(s_->obs, s_->res), "step");
    const node::StepResult<T, PyBounds>& r = s_->res;
    py::list outcome;
    py::array_t<std::int32_t> feature(r.count);
    py::array_t<double> d2(r.count);
    for (int i = 0; i < r.count; ++i) {
      outcome.append(outcome_name(r.outcome[i]));
      feature.mutable_at(i) = r.feature[i];
      d2.mutable_at(i) = r.d2[i];
    }
    py::dict o;
    o["outcome"] = outcome;
    o["feature"] = feature;
    o["d2"] = d2;
    o["diagnostics"] = diagnostics(r.diag);
    return o;
  }
  py::array_t<double> pose() const {
    const Pose2<T> x = s_->step.slam().pose();
    py::array_t<double> a(3);
    a.mutable_at(0) = x.x;
    a.mutable_at(1) = x.y;
    a.mutable_at(2) = x.theta;
    return a;
  }
  py::tuple landmarks() const {
    const auto& s = s_->step.slam();
    const int n = s.landmarks();
    py::array_t<std::int32_t> ids(n);
    py::array_t<double> xy({n, 2});
    for (int j = 0; j < n; ++j) {
      ids.mutable_at(j) = s.id(j);
      xy.mutable_at(j, 0) = s.landmark(j).x();
      xy.mutable_at(j, 1) = s.landmark(j).y();
    }
    return py::make_tuple(ids, xy);
  }
  py::array_t<double> covariance() const {
    const auto& s = s_->step.slam();
    const int d = s.dim();
    py::array_t<double> P({d, d});
    for (int r = 0; r < d; ++r)
      for (int c = 0; c < d; ++c) P.mutable_at(r, c) = s.cov(r, c);
    return P;
  }

 private:
  struct State {
    node::SlamStep<T, PyBounds> step;
    Observations<T, PyBounds> obs;
    node::StepResult<T, PyBounds> res;
  };
  std::unique_ptr<State> s_;
};

class PySimulator {
 public:
  PySimulator(const std::string& path, std::uint64_t seed) : sc_(host::load_scenario(path)), sim_(sc_, seed) {}
  py::object step() {
    host::SimStep s;
    if (!sim_.step(s)) return py::none();
    const py::ssize_t k = static_cast<py::ssize_t>(s.observations.size());
    py::array_t<double> z({k, py::ssize_t(2)});
    py::array_t<double> R({k, py::ssize_t(2), py::ssize_t(2)});
    py::array_t<std::int32_t> truth(k);
    for (py::ssize_t i = 0; i < k; ++i) {
      const host::SimObservation& o = s.observations[static_cast<std::size_t>(i)];
      z.mutable_at(i, 0) = o.z.x();
      z.mutable_at(i, 1) = o.z.y();
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) R.mutable_at(i, a, b) = o.R(a, b);
      truth.mutable_at(i) = o.truth;
    }
    py::dict d;
    d["t_s"] = s.t_s;
    d["true_pose"] = py::make_tuple(s.true_pose.x, s.true_pose.y, s.true_pose.theta);
    d["v_mps"] = s.v_mps;
    d["w_radps"] = s.w_radps;
    d["scan"] = s.scan;
    d["z"] = z;
    d["R"] = R;
    d["truth"] = truth;
    return d;
  }
  py::array_t<double> landmarks() const {
    const py::ssize_t n = static_cast<py::ssize_t>(sc_.landmarks.size());
    py::array_t<double> a({n, py::ssize_t(2)});
    for (py::ssize_t j = 0; j < n; ++j) {
      a.mutable_at(j, 0) = sc_.landmarks[static_cast<std::size_t>(j)].x();
      a.mutable_at(j, 1) = sc_.landmarks[static_cast<std::size_t>(j)].y();
    }
    return a;
  }
  const host::Scenario& scenario() const { return sc_; }

 private:
  host::Scenario sc_;
  host::Simulator sim_;
};

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "geojcbb: data association for 2D EKF-SLAM (GEOJCBB and its baselines), in double at host bounds.";
  g_error = py::exception<std::exception>(m, "GeojcbbError", PyExc_RuntimeError);
  m.attr("NEW_FEATURE") = kNewFeature;
  m.attr("UNMATCHED") = kUnmatched;
  m.attr("MAX_OBSERVATIONS") = PyBounds::kMaxObservations;
  m.attr("MAX_CANDIDATES") = PyBounds::kMaxCandidates;
  m.attr("MAX_GROUPS") = PyBounds::kMaxGroups;
  m.attr("MAX_JCBB_NODES") = PyBounds::kMaxJcbbNodes;
  m.attr("MAX_LANDMARKS") = PyBounds::kMaxLandmarks;
  py::list names;
  for (int k = 0; k < kStrategyCount; ++k) names.append(to_string(static_cast<Strategy>(k)));
  m.attr("STRATEGIES") = names;
  py::dict suffixes;  // the tools' suffix letters (core/presets.hpp): letter -> what it switches in
  for (const PresetSuffix& p : kPresetSuffixes) suffixes[py::str(std::string(1, p.letter))] = p.what;
  m.attr("PRESET_SUFFIXES") = suffixes;
  py::list opts;
  for (const options::Info& o : options::kInfo) {
    py::dict d;
    d["name"] = o.name;
    d["type"] = o.type;
    d["default"] = o.default_text;
    d["unit"] = o.unit;
    d["meaning"] = o.meaning;
    opts.append(d);
  }
  m.attr("OPTIONS") = opts;
  static const std::string assoc_doc = std::string(
                                           R"doc(Associates one scan's observations with the predicted candidates.

z: (m, 2) observations (range [m], bearing [rad]); R: (m, 2, 2) their noise [m^2, rad^2];
h: (n, 2) predicted (range [m], bearing [rad]); C: (2n, 2n) H P H^T, candidate j at rows 2j, 2j+1;
ids: (n,) feature ids >= 0. strategy: one of STRATEGIES, optionally with the suffixes of PRESET_SUFFIXES ("JCBB+V", "PCJCBB+RL").
Returns a dict: feature (m,) int32 (id, NEW_FEATURE or UNMATCHED), candidate (m,) (index or -1),
d2 (m,), pairings, joint_d2, jointly_compatible, diagnostics (dict of counters).
Raises GeojcbbError (.status: kNonFinite, kInvalidInput, kCapacityExceeded, kNotSymmetric,
kNotPositiveDefinite, kNoConvergence); TypeError for an unknown keyword.
Options (keywords; OPTIONS lists them; the association reads its own):
)doc") + options_doc();
  static const std::string slam_doc =
      std::string(
          "strategy: one of STRATEGIES, optionally with the suffixes of PRESET_SUFFIXES. Options "
          "(keywords; OPTIONS lists them):\n") +
      options_doc() + "Raises GeojcbbError (kInvalidInput for an option outside its range), TypeError.";
  m.def("associate", &associate_py, py::arg("z"), py::arg("R"), py::arg("h"), py::arg("C"), py::arg("ids"),
        py::arg("strategy") = "PCJCBB", assoc_doc.c_str());
  py::class_<PySlam>(m, "Slam", "One EKF-SLAM step with data association (node::SlamStep<double>).")
      .def(py::init<const std::string&, const py::kwargs&>(), py::arg("strategy") = "PCJCBB+RL", slam_doc.c_str())
      .def("reset", &PySlam::reset, py::arg("x0"), py::arg("P0"),
           "Clears the map. x0 = (x [m], y [m], theta [rad]); P0 (3, 3).")
      .def("predict", &PySlam::predict, py::arg("v_mps"), py::arg("w_radps"), py::arg("dt_s"), py::arg("sigma_v_mps"),
           py::arg("sigma_w_radps"), "One odometry interval.")
      .def("step", &PySlam::step, py::arg("z"), py::arg("R"),
           "One scan: z (m, 2) [m, rad], R (m, 2, 2). Returns outcome (list of str), feature, d2, diagnostics.")
      .def_property_readonly("pose", &PySlam::pose, "(x [m], y [m], theta [rad])")
      .def_property_readonly("landmarks", &PySlam::landmarks, "(ids (k,), positions (k, 2) [m])")
      .def_property_readonly("covariance", &PySlam::covariance, "P, (3 + 2k, 3 + 2k)");
  py::class_<PySimulator>(m, "Simulator", "The scenario simulator (host_tools/sim, docs/simulator.md).")
      .def(py::init<const std::string&, std::uint64_t>(), py::arg("scenario_path"), py::arg("seed") = 1,
           "Loads a scenario JSON file (RuntimeError on a bad file).")
      .def(
          "step", &PySimulator::step,
          "Advances one control interval; None once the laps are done. Returns t_s [s], true_pose (x, y, theta),\n"
          "v_mps, w_radps (noisy odometry), scan (bool), z (k, 2), R (k, 2, 2), truth (k,) (landmark index, -1: clutter).")
      .def_property_readonly("landmarks", &PySimulator::landmarks, "true landmark positions (L, 2) [m]")
      .def_property_readonly("dt_s", [](const PySimulator& s) { return s.scenario().dt_s; })
      .def_property_readonly("sigma_v_mps", [](const PySimulator& s) { return s.scenario().sigma_v_mps; })
      .def_property_readonly("sigma_w_radps", [](const PySimulator& s) { return s.scenario().sigma_w_radps; })
      .def_property_readonly("max_range_m", [](const PySimulator& s) { return s.scenario().max_range_m; })
      .def_property_readonly("fov_rad", [](const PySimulator& s) { return s.scenario().fov_rad; });
}
