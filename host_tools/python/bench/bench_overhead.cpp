// The C++ side of the Python bindings' checks, at the bindings' capacities (PyBounds) in double.
//   python_overhead_cpp --reference   reads scenes from stdin and prints each one's association, for
//                                     tests/test_geojcbb.py (same answers as the bindings)
//   python_overhead_cpp --bench N     reads one scene and prints the median associate() time over N
//                                     calls in microseconds, for bench_overhead.py (not a test)
// Scene format (whitespace separated): strategy radius_m m n, then z (2m), R (4m), ids (n), h (2n),
// C (4n^2, row-major). Output per scene: status, then m features, m d2 (%.17g), joint_d2, pairings, nodes.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb/associate.hpp"
#include "geojcbb_host/guarded_main.hpp"

using namespace geojcbb;
using PyBounds = Bounds<64, 128, 8, 200000, 500>;  // as host_tools/python/geojcbb_py.cpp

namespace {
struct State {
  Observations<double, PyBounds> obs;
  Prediction<double, PyBounds> pred;
  AssociationWorkspace<double, PyBounds> ws;
  Association<double, PyBounds> out;
};

bool read_scene(std::istream& in, State& s, AssociationConfig<double, PyBounds>& cfg, Status& st) {
  std::string name;
  double radius = 0;
  int m = 0, n = 0;
  if (!(in >> name >> radius >> m >> n)) return false;
  Strategy strategy = Strategy::kGeojcbb;
  for (int k = 0; k < kStrategyCount; ++k)
    if (name == to_string(static_cast<Strategy>(k))) strategy = static_cast<Strategy>(k);
  StepSettings<double> p;
  p.local_radius_m = radius;
  st = make_strategy(strategy, p, cfg);
  s.obs.count = m;
  for (int i = 0; i < m; ++i) in >> s.obs.z[i].x() >> s.obs.z[i].y();
  for (int i = 0; i < m; ++i) in >> s.obs.R[i](0, 0) >> s.obs.R[i](0, 1) >> s.obs.R[i](1, 0) >> s.obs.R[i](1, 1);
  s.pred.count = n;
  for (int j = 0; j < n; ++j) in >> s.pred.id[j];
  for (int j = 0; j < n; ++j) in >> s.pred.h[j].x() >> s.pred.h[j].y();
  Eigen::MatrixXd C(2 * n, 2 * n);  // dense in the file; the prediction holds its lower blocks
  for (int r = 0; r < 2 * n; ++r)
    for (int c = 0; c < 2 * n; ++c) in >> C(r, c);
  return static_cast<bool>(in) && s.pred.C.assign_dense(C) == Status::kOk;
}
}  // namespace

namespace {

int run(int argc, char** argv) {
  std::unique_ptr<State> s(new State());
  AssociationConfig<double, PyBounds> cfg;
  Status st = Status::kOk;
  if (argc >= 2 && std::strcmp(argv[1], "--reference") == 0) {
    while (read_scene(std::cin, *s, cfg, st)) {
      if (st == Status::kOk) st = associate(s->obs, s->pred, cfg, s->ws, s->out);
      std::printf("%s", to_string(st));
      if (st == Status::kOk) {
        for (int i = 0; i < s->out.count; ++i) std::printf(" %d", s->out.feature[i]);
        for (int i = 0; i < s->out.count; ++i) std::printf(" %.17g", s->out.d2[i]);
        std::printf(" %.17g %d %u", s->out.joint_d2, s->out.pairings, s->out.diag.jcbb_nodes);
      }
      std::printf("\n");
    }
    return 0;
  }
  if (argc >= 3 && std::strcmp(argv[1], "--bench") == 0) {
    const int calls = std::max(1, std::atoi(argv[2]));
    if (!read_scene(std::cin, *s, cfg, st) || st != Status::kOk) return 1;
    std::vector<double> us;
    us.reserve(static_cast<std::size_t>(calls));
    for (int k = 0; k < calls; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      const Status a = associate(s->obs, s->pred, cfg, s->ws, s->out);
      const auto t1 = std::chrono::steady_clock::now();
      if (a != Status::kOk) return 1;
      us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    }
    std::nth_element(us.begin(), us.begin() + calls / 2, us.end());
    std::printf("%.3f\n", us[static_cast<std::size_t>(calls / 2)]);
    return 0;
  }
  std::fprintf(stderr, "usage: %s --reference | --bench CALLS  (scene(s) on stdin)\n", argv[0]);
  return 2;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
