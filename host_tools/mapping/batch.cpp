// host_tools/mapping: the batch reference (batch.hpp).
#include "geojcbb_host/batch.hpp"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "geojcbb/ekf/motion.hpp"

namespace geojcbb::host {

namespace {

/// An angle to (-pi, pi], differentiable (Ceres' Jets and double alike).
template <typename T>
T wrapped(const T& a) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(a), cos(a));
}

/// The square root of a covariance's inverse (U with U^T U = Sigma^-1), its eigenvalues floored at
/// kFloor: the odometry's covariance is rank 2 over one interval (v and w drive three components),
/// and the floor, (1 mm)^2 and (1 mrad)^2, keeps the direction the model says is exact finite.
Eigen::Matrix3d sqrt_information(const Eigen::Matrix3d& cov) {
  constexpr double kFloor = 1e-6;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (cov + cov.transpose()));
  const Eigen::Vector3d inv_sd = es.eigenvalues().cwiseMax(kFloor).cwiseSqrt().cwiseInverse();
  return inv_sd.asDiagonal() * es.eigenvectors().transpose();
}
Eigen::Matrix2d sqrt_information(const Eigen::Matrix2d& cov) {
  const Eigen::LLT<Eigen::Matrix2d> llt(cov.inverse());
  return llt.matrixU();
}

/// The odometry from pose a to pose b, in a's frame, against the measured one.
struct OdometryFactor {
  Pose2<double> rel;
  Eigen::Matrix3d U;
  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    const T e[3] = {c * dx + s * dy - T(rel.x), -s * dx + c * dy - T(rel.y), wrapped(T(b[2] - a[2] - T(rel.theta)))};
    for (int i = 0; i < 3; ++i) r[i] = T(U(i, 0)) * e[0] + T(U(i, 1)) * e[1] + T(U(i, 2)) * e[2];
    return true;
  }
};

/// A range-bearing observation of landmark l from pose x through the mount (core/range_bearing.hpp).
struct ObservationFactor {
  Mount<double> m;
  Eigen::Vector2d z;
  Eigen::Matrix2d U;
  template <typename T>
  bool operator()(const T* x, const T* l, T* r) const {
    using std::atan2;
    using std::cos;
    using std::sin;
    using std::sqrt;
    const T c = cos(x[2]), s = sin(x[2]);
    const T sx = x[0] + c * T(m.x) - s * T(m.y), sy = x[1] + s * T(m.x) + c * T(m.y);
    const T dx = l[0] - sx, dy = l[1] - sy;
    const T e[2] = {sqrt(dx * dx + dy * dy) - T(z.x()), wrapped(T(atan2(dy, dx) - x[2] - T(m.theta) - T(z.y())))};
    for (int i = 0; i < 2; ++i) r[i] = T(U(i, 0)) * e[0] + T(U(i, 1)) * e[1];
    return true;
  }
};

/// A weak anchor of a pose at its start, where a kidnap broke the odometry chain (10 m, 1 rad): the
/// landmarks place it, the anchor only removes the gauge of a pose nothing else holds.
struct AnchorFactor {
  Pose2<double> at;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = (x[0] - T(at.x)) / T(10);
    r[1] = (x[1] - T(at.y)) / T(10);
    r[2] = wrapped(T(x[2] - T(at.theta)));
    return true;
  }
};

/// The prediction `in` composed onto rel (the pose since the last scan, in its frame), its
/// covariance propagated as the filter's (ekf::Slam::predict).
void propagate(const RunInput& in, Pose2<double>& rel, Eigen::Matrix3d& cov) {
  if (in.increment) {
    const ekf::PoseIncrement<double> u{in.dx_m, in.dy_m, in.dtheta_rad, in.increment_cov};
    Mat3<double> F, J;
    rel = ekf::compose(rel, u, &F, &J);
    cov = F * cov * F.transpose() + J * u.cov * J.transpose();
    return;
  }
  const ekf::Odometry<double> u{in.v_mps, in.w_radps, in.dt_s, in.sigma_v_mps, in.sigma_w_radps};
  Mat3<double> F;
  Mat32<double> G;
  rel = ekf::move(rel, u, &F, &G);
  const Eigen::Matrix2d Q =
      Eigen::Vector2d(u.sigma_v_mps * u.sigma_v_mps, u.sigma_w_radps * u.sigma_w_radps).asDiagonal();
  cov = F * cov * F.transpose() + G * Q * G.transpose();
}

/// The last scan's pose index.
int k_last(const BatchProblem& p) { return static_cast<int>(p.initial.size()) - 1; }

}  // namespace

BatchProblem batch_problem(RunSource& src, const BatchRecorder& rec, const std::vector<TracePoint>& trace,
                           const Mount<double>& mount, bool by_labels) {
  BatchProblem p;
  p.mount = mount;
  std::map<long long, int> index;  // landmark key (an id, or a label) -> its index
  Pose2<double> rel{};
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  bool chained = true;
  std::size_t next = 0;  // the recorder's next scan
  const auto& scans = rec.scans();
  src.rewind();
  RunInput in;
  std::size_t input = 0;  // the trace holds the pose after every input, in order
  for (; src.next(in); ++input) {
    if (in.relocalise) {
      chained = false;
      continue;
    }
    if (!in.scan) {
      propagate(in, rel, cov);
      // The filter's trace time of a prediction (run_inputs): after it, for one over (v, w, dt).
      if (!p.initial.empty()) p.path.push_back({in.increment ? in.t_s : in.t_s + in.dt_s, k_last(p), rel});
      continue;
    }
    const int k = static_cast<int>(p.initial.size());
    p.t_s.push_back(in.t_s);
    if (input >= trace.size()) throw std::runtime_error("batch: the filter's trace is shorter than the run's inputs");
    p.initial.push_back(trace[input].pose);
    p.have_truth.push_back(in.have_truth ? 1 : 0);
    p.truth.push_back(in.true_pose);
    if (k > 0) {
      p.relative.push_back(rel);
      p.relative_cov.push_back(cov);
      p.chained.push_back(chained ? 1 : 0);
    }
    rel = Pose2<double>{};
    cov.setZero();
    chained = true;
    p.path.push_back({in.t_s, k, rel});
    while (next < scans.size() && scans[next].t_s < in.t_s) ++next;
    if (next == scans.size() || scans[next].t_s != in.t_s) continue;  // a scan the steps did not use (lost)
    const BatchRecorder::Scan& sc = scans[next++];
    for (std::size_t i = 0; i < sc.obs.size(); ++i) {
      const long long key = by_labels ? sc.obs[i].truth : sc.id[i];
      if (key < 0) continue;
      auto [it, added] = index.emplace(key, static_cast<int>(p.landmark_initial.size()));
      if (added) {
        const Vec2<double> l = inverse_observe(p.initial.back(), mount, Vec2<double>(sc.obs[i].z));
        p.landmark_initial.emplace_back(l.x(), l.y());
      }
      p.obs.push_back({k, it->second, sc.obs[i].z, sc.obs[i].R});
    }
  }
  src.rewind();
  if (input != trace.size()) throw std::runtime_error("batch: the filter's trace is not one pose per input");
  return p;
}

BatchResult solve_batch(const BatchProblem& p, const BatchOptions& o) {
  if (p.initial.empty()) throw std::invalid_argument("batch: no scans");
  std::vector<std::array<double, 3>> x(p.initial.size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = {p.initial[k].x, p.initial[k].y, p.initial[k].theta};
  std::vector<std::array<double, 2>> l(p.landmark_initial.size());
  for (std::size_t j = 0; j < l.size(); ++j) l[j] = {p.landmark_initial[j].x(), p.landmark_initial[j].y()};
  ceres::Problem problem;
  for (auto& xk : x) problem.AddParameterBlock(xk.data(), 3);
  problem.SetParameterBlockConstant(x[0].data());  // the filter's start: the map's frame
  for (std::size_t k = 1; k < x.size(); ++k) {
    if (p.chained[k - 1]) {
      auto* f = new ceres::AutoDiffCostFunction<OdometryFactor, 3, 3, 3>(
          new OdometryFactor{p.relative[k - 1], sqrt_information(p.relative_cov[k - 1])});
      problem.AddResidualBlock(f, nullptr, x[k - 1].data(), x[k].data());
    } else {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AnchorFactor, 3, 3>(new AnchorFactor{p.initial[k]}),
                               nullptr, x[k].data());
    }
  }
  for (const BatchObservation& b : p.obs) {
    auto* f = new ceres::AutoDiffCostFunction<ObservationFactor, 2, 3, 2>(
        new ObservationFactor{p.mount, b.z, sqrt_information(b.R)});
    ceres::LossFunction* loss = o.huber > 0 ? new ceres::HuberLoss(o.huber) : nullptr;
    problem.AddResidualBlock(f, loss, x[static_cast<std::size_t>(b.pose)].data(),
                             l[static_cast<std::size_t>(b.landmark)].data());
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.max_num_iterations = o.max_iterations;
  so.num_threads = 1;  // the same result on every machine
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary sum;
  const auto a = std::chrono::steady_clock::now();
  ceres::Solve(so, &problem, &sum);
  BatchResult r;
  r.solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
  r.iterations = static_cast<int>(sum.iterations.size());
  r.initial_cost = sum.initial_cost;
  r.final_cost = sum.final_cost;
  r.converged = sum.termination_type == ceres::CONVERGENCE;
  r.report = sum.BriefReport();
  for (const auto& xk : x) r.poses.push_back({xk[0], xk[1], xk[2]});
  for (const BatchProblem::Between& b : p.path) {  // each solved scan pose, and the odometry on from it
    const auto& xk = x[static_cast<std::size_t>(b.pose)];
    const ekf::PoseIncrement<double> u{b.rel.x, b.rel.y, b.rel.theta, Mat3<double>::Zero()};
    r.trace.push_back({b.t_s, ekf::compose(Pose2<double>{xk[0], xk[1], xk[2]}, u)});
  }
  for (const auto& lj : l) r.landmarks.emplace_back(lj[0], lj[1]);
  return r;
}

double mean_position_error(const BatchProblem& p, const std::vector<Pose2<double>>& poses) {
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < poses.size() && k < p.truth.size(); ++k) {
    if (!p.have_truth[k]) continue;
    sum += std::hypot(poses[k].x - p.truth[k].x, poses[k].y - p.truth[k].y);
    ++n;
  }
  return n > 0 ? sum / n : NAN;
}

std::array<double, 3> batch_errors(RunSource& src, const BatchRecorder& rec, const RunResult& r, const RunOptions& ro) {
  const StepSettings<double> ss = step_settings(ro, src.sensor);
  const Mount<double> mount{ss.sensor_x_m, ss.sensor_y_m, ss.sensor_theta_rad};
  const BatchProblem own = batch_problem(src, rec, r.trace, mount, false);
  const BatchProblem labels = batch_problem(src, rec, r.trace, mount, true);
  return {mean_position_error(own, own.initial), mean_position_error(own, solve_batch(own, BatchOptions{}).poses),
          mean_position_error(labels, solve_batch(labels, BatchOptions{}).poses)};
}

}  // namespace geojcbb::host
