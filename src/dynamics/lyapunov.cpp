#include "gear_dynamics/dynamics/lyapunov.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <stdexcept>

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics {

namespace {

// Gram-Schmidt of the columns of V (tangent vectors in state units) in the scaled norm; returns
// ln r_kk per column.
std::vector<double> orthonormalise(Eigen::MatrixXd& V, const Eigen::VectorXd& scale) {
  Eigen::MatrixXd U = scale.cwiseInverse().asDiagonal() * V;
  std::vector<double> log_r(U.cols());
  for (Eigen::Index k = 0; k < U.cols(); ++k) {
    for (Eigen::Index j = 0; j < k; ++j) U.col(k) -= U.col(j).dot(U.col(k)) * U.col(j);
    const double r = U.col(k).norm();
    if (!(r > 0) || !std::isfinite(r))
      throw std::runtime_error("lyapunov_spectrum: the tangent vectors collapsed or overflowed; orthonormalise more often");
    U.col(k) /= r;
    log_r[k] = std::log(r);
  }
  V = scale.asDiagonal() * U;
  return log_r;
}

// The torsional model's (delta, delta_dot) with its two tangent vectors: the kernel's located
// steps (kernel::rk4_step_tangent), whose state is rk4_step's bit for bit.
class TorsionalFlow {
 public:
  TorsionalFlow(const GearLaneSpec& lane, double h)
      : g_(derive(lane.gear)), mesh_(g_, h), h_(h), mu_(lane.mu), load_(lane.load),
        d_(lane.initial.deflection), v_(lane.initial.velocity) {}
  static constexpr int kDimension = 2;
  const GearPair& gear() const { return g_; }
  const MeshSchedule& mesh() const { return mesh_; }
  void step(std::int64_t n) {
    kernel::rk4_step_tangent(mesh_.plan(n), h_, g_.in.backlash, g_.damping_coefficient, g_.q3, mu_, load_, load_, d_, v_,
                             t_);
  }
  double deflection() const { return d_; }
  bool finite() const { return std::isfinite(d_) && std::isfinite(v_); }
  Eigen::MatrixXd vectors() const {
    Eigen::MatrixXd V(2, 2);
    for (int k = 0; k < 2; ++k) V(0, k) = t_.xi[k], V(1, k) = t_.eta[k];
    return V;
  }
  void set_vectors(const Eigen::MatrixXd& V) {
    for (int k = 0; k < 2; ++k) t_.xi[k] = V(0, k), t_.eta[k] = V(1, k);
  }
  double trace_integral() const { return t_.trace_integral; }

 private:
  GearPair g_;
  MeshSchedule mesh_;
  double h_, mu_, load_, d_, v_;
  kernel::Tangent t_;
};

// The bearings model's state with its ten tangent vectors and the trace's integral, one state of
// the engine's seam (model_step.hpp): the vectors follow J V and the integral tr J through the
// same located RK4 sub-steps as the state, which is bearings_step's bit for bit.
struct BearingsTangentModel {
  static constexpr int kN = BearingsModel::kStates;
  static constexpr int kStates = kN + kN * kN + 1;
  using State = Eigen::Matrix<double, kStates, 1>;
  const BearingsModel& model;
  double deflection(const State& y) const { return model.deflection(y.head<kN>()); }
  double deflection_rate(const State& y) const { return model.deflection_rate(y.head<kN>()); }
  State derivative(int branch, const State& y, const model_step::MeshPoint& p) const {
    const BearingsModel::State x = y.head<kN>();
    const BearingsModel::Jacobian J = model.jacobian(branch, x, p);
    State dy;
    dy.head<kN>() = model.derivative(branch, x, p);
    Eigen::Map<Eigen::Matrix<double, kN, kN>>(dy.data() + kN) =
        J * Eigen::Map<const Eigen::Matrix<double, kN, kN>>(y.data() + kN);
    dy[kStates - 1] = J.trace();
    return dy;
  }
};

class BearingsFlow {
 public:
  static constexpr int kN = BearingsTangentModel::kN;
  BearingsFlow(const GearLaneSpec& lane, double h)
      : g_(derive(lane.gear)), mesh_(g_, h), model_(g_), tangent_{model_}, h_(h), mu_(lane.mu), load_(lane.load) {
    y_ = BearingsTangentModel::State::Zero();
    y_[BearingsModel::kDelta] = lane.initial.deflection;  // as BearingsRealization starts
    y_[BearingsModel::kDeltaDot] = lane.initial.velocity;
  }
  static constexpr int kDimension = kN;
  const GearPair& gear() const { return g_; }
  const MeshSchedule& mesh() const { return mesh_; }
  void step(std::int64_t n) { bearings_step_of(tangent_, g_, mesh_, h_, mu_, n, load_, load_, y_); }
  double deflection() const { return model_.deflection(y_.head<kN>()); }
  bool finite() const { return y_.head<kN>().allFinite(); }
  Eigen::MatrixXd vectors() const { return Eigen::Map<const Eigen::Matrix<double, kN, kN>>(y_.data() + kN); }
  void set_vectors(const Eigen::MatrixXd& V) { Eigen::Map<Eigen::Matrix<double, kN, kN>>(y_.data() + kN) = V; }
  double trace_integral() const { return y_[BearingsTangentModel::kStates - 1]; }

 private:
  GearPair g_;
  MeshSchedule mesh_;
  BearingsModel model_;
  BearingsTangentModel tangent_;
  double h_, mu_, load_;
  BearingsTangentModel::State y_;
};

// The spectrum of one flow (TorsionalFlow or BearingsFlow) over options.duration.
template <class Flow>
LyapunovSpectrum spectrum_of(Flow& flow, double load, double h, const SpectrumOptions& o) {
  constexpr int dim = Flow::kDimension;
  const double b = flow.gear().in.backlash;
  Eigen::VectorXd scale(dim);
  for (int c = 0; c < dim; ++c) scale[c] = c % 2 == 0 ? b : std::sqrt(2.0 * std::fabs(load) * b);
  if (!o.scale.empty()) {
    if (static_cast<int>(o.scale.size()) != dim)
      throw std::invalid_argument("lyapunov_spectrum: " + std::to_string(dim) + " scales, one per state component (given " +
                                  std::to_string(o.scale.size()) + ")");
    for (int c = 0; c < dim; ++c) scale[c] = o.scale[c];
  }
  if (!(scale.minCoeff() > 0)) throw std::invalid_argument("lyapunov_spectrum: scales must be > 0");
  const auto steps_of = [&](double t) {
    const double n = t / h;
    if (std::fabs(n - std::round(n)) > 1e-6) throw std::invalid_argument("lyapunov_spectrum: times must be grid points");
    return static_cast<std::int64_t>(std::llround(n));
  };
  const std::int64_t n_end = steps_of(o.duration);
  std::vector<std::int64_t> edges;
  for (double w : o.windows) {
    const std::int64_t e = steps_of(w);
    if (e < 0 || e > n_end || (!edges.empty() && e <= edges.back()))
      throw std::invalid_argument("lyapunov_spectrum: window edges increase within [0, duration]");
    edges.push_back(e);
  }

  flow.set_vectors(Eigen::MatrixXd(scale.asDiagonal()));  // unit vectors of the scaled state
  std::vector<double> sum(dim, 0.0);
  LyapunovSpectrum out;
  std::int64_t since = 0, counted = 0;
  std::size_t next_edge = 0;
  while (next_edge < edges.size() && edges[next_edge] == 0) {
    out.edges.push_back(SpectrumEdge{0.0, std::vector<double>(dim, 0.0), 0.0});
    ++next_edge;
  }
  for (std::int64_t n = 0; n < n_end; ++n) {
    flow.step(n);
    if (!flow.finite())
      throw std::runtime_error("lyapunov_spectrum: the gear model diverged at t = " + std::to_string((n + 1) * h) + " s");
    if (flow.deflection() - flow.mesh().transmission_error((n + 1) * h) <= b) out.last_separation = (n + 1) * h;
    ++since;
    const bool edge = next_edge < edges.size() && edges[next_edge] == n + 1;
    if (since == o.orthonormalise_every || edge || n + 1 == n_end) {
      Eigen::MatrixXd V = flow.vectors();
      const std::vector<double> lr = orthonormalise(V, scale);
      flow.set_vectors(V);
      for (int k = 0; k < dim; ++k) sum[k] += lr[k];
      since = 0;
      ++counted;
      if (o.record_every > 0 && (counted % o.record_every == 0 || n + 1 == n_end)) {
        out.time.push_back((n + 1) * h);
        out.running.push_back(sum[0] / ((n + 1) * h));
      }
    }
    if (edge) {
      out.edges.push_back(SpectrumEdge{(n + 1) * h, sum, flow.trace_integral()});
      ++next_edge;
    }
  }
  const double T = n_end * h;
  for (int k = 0; k < dim; ++k) out.exponent.push_back(sum[k] / T);
  out.trace = flow.trace_integral() / T;
  for (std::size_t k = 1; k < out.edges.size(); ++k) out.windows.push_back(window_between(out.edges[k - 1], out.edges[k]));
  return out;
}

}  // namespace

LyapunovSpectrum lyapunov_spectrum(const GearLaneSpec& lane, double h, const SpectrumOptions& o) {
  if (o.orthonormalise_every < 1) throw std::invalid_argument("lyapunov_spectrum: orthonormalise_every must be >= 1");
  if (lane.gear.model == GearModel::kBearings) {
    BearingsFlow flow(lane, h);
    return spectrum_of(flow, lane.load, h, o);
  }
  TorsionalFlow flow(lane, h);
  return spectrum_of(flow, lane.load, h, o);
}

SpectrumWindow window_between(const SpectrumEdge& from, const SpectrumEdge& to) {
  SpectrumWindow w;
  w.start = from.time;
  w.end = to.time;
  const double len = w.end - w.start;
  for (std::size_t k = 0; k < to.log_r.size(); ++k) w.exponent.push_back((to.log_r[k] - from.log_r[k]) / len);
  w.trace = (to.trace_integral - from.trace_integral) / len;
  return w;
}

std::vector<LyapunovResult> largest_lyapunov(LaneSystem& sys, const LyapunovOptions& o) {
  const int lanes = sys.lanes(), dim = sys.dimension();
  if (lanes % 2 != 0) throw std::invalid_argument("largest_lyapunov: lanes come in pairs (reference, perturbed)");
  if (o.renormalise_every < 1) throw std::invalid_argument("largest_lyapunov: renormalise_every must be >= 1");
  std::vector<double> scale = o.scale;
  if (scale.empty()) scale.assign(dim, 1.0);
  if (static_cast<int>(scale.size()) != dim) throw std::invalid_argument("largest_lyapunov: one scale per component");
  const double h = sys.time_step();
  const std::int64_t n_transient = std::llround(o.transient / h);
  const std::int64_t intervals = std::llround(o.duration / h) / o.renormalise_every;
  const int pairs = lanes / 2;
  std::vector<double> x(dim);

  // Transient: the perturbed lane follows the reference exactly.
  for (int p = 0; p < pairs; ++p) {
    for (int c = 0; c < dim; ++c) x[c] = sys.state(2 * p, c);
    sys.set_state(2 * p + 1, x.data());
  }
  while (sys.step_index() < n_transient) sys.step();

  const double e = 1.0 / std::sqrt(static_cast<double>(dim));
  for (int p = 0; p < pairs; ++p) {
    for (int c = 0; c < dim; ++c) x[c] = sys.state(2 * p, c) + o.separation * e * scale[c];
    sys.set_state(2 * p + 1, x.data());
  }
  std::vector<LyapunovResult> res(pairs);
  std::vector<double> sum(pairs, 0.0);
  for (auto& r : res) {
    r.max_log_growth = -std::numeric_limits<double>::infinity();
    r.min_log_growth = std::numeric_limits<double>::infinity();
  }
  const double interval_time = static_cast<double>(o.renormalise_every) * h;
  for (std::int64_t i = 1; i <= intervals; ++i) {
    for (std::int64_t s = 0; s < o.renormalise_every; ++s) sys.step();
    for (int p = 0; p < pairs; ++p) {
      double d2 = 0;
      for (int c = 0; c < dim; ++c) {
        const double dc = (sys.state(2 * p + 1, c) - sys.state(2 * p, c)) / scale[c];
        d2 += dc * dc;
      }
      const double d = std::sqrt(d2);
      if (!(d > 0) || !std::isfinite(d))
        throw std::runtime_error("largest_lyapunov: the separation collapsed to 0 or became non-finite; "
                                 "choose a larger separation or renormalise more often");
      const double g = std::log(d / o.separation);
      sum[p] += g;
      LyapunovResult& r = res[p];
      r.max_log_growth = std::max(r.max_log_growth, g);
      r.min_log_growth = std::min(r.min_log_growth, g);
      const double f = o.separation / d;
      for (int c = 0; c < dim; ++c)
        x[c] = sys.state(2 * p, c) + (sys.state(2 * p + 1, c) - sys.state(2 * p, c)) * f;
      sys.set_state(2 * p + 1, x.data());
      if (o.record_every > 0 && (i % o.record_every == 0 || i == intervals)) {
        r.time.push_back(sys.time());
        r.running.push_back(sum[p] / (static_cast<double>(i) * interval_time));
      }
    }
  }
  for (int p = 0; p < pairs; ++p) {
    res[p].intervals = intervals;
    res[p].exponent = intervals > 0 ? sum[p] / (static_cast<double>(intervals) * interval_time) : 0.0;
  }
  return res;
}

}  // namespace gear_dynamics
