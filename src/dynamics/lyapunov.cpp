#include "gear_dynamics/dynamics/lyapunov.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "gear_dynamics/engine/rk4_kernel.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics {

namespace {

// Gram-Schmidt of the two tangent vectors in the scaled norm; returns ln r11, ln r22.
void orthonormalise(kernel::Tangent& t, const double scale[2], double log_r[2]) {
  double u[2][2];
  for (int k = 0; k < 2; ++k) u[k][0] = t.xi[k] / scale[0], u[k][1] = t.eta[k] / scale[1];
  const double r11 = std::hypot(u[0][0], u[0][1]);
  u[0][0] /= r11, u[0][1] /= r11;
  const double r12 = u[0][0] * u[1][0] + u[0][1] * u[1][1];
  u[1][0] -= r12 * u[0][0], u[1][1] -= r12 * u[0][1];
  const double r22 = std::hypot(u[1][0], u[1][1]);
  u[1][0] /= r22, u[1][1] /= r22;
  if (!(r11 > 0) || !(r22 > 0) || !std::isfinite(r11) || !std::isfinite(r22))
    throw std::runtime_error("lyapunov_spectrum: the tangent vectors collapsed or overflowed; orthonormalise more often");
  log_r[0] = std::log(r11);
  log_r[1] = std::log(r22);
  for (int k = 0; k < 2; ++k) t.xi[k] = u[k][0] * scale[0], t.eta[k] = u[k][1] * scale[1];
}

}  // namespace

LyapunovSpectrum lyapunov_spectrum(const GearLaneSpec& lane, double h, const SpectrumOptions& o) {
  if (o.orthonormalise_every < 1) throw std::invalid_argument("lyapunov_spectrum: orthonormalise_every must be >= 1");
  const GearPair g = derive(lane.gear);
  const MeshSchedule mesh(g, h);
  const double b = g.in.backlash;
  double scale[2] = {b, std::sqrt(2.0 * std::fabs(lane.load) * b)};
  if (!o.scale.empty()) {
    if (o.scale.size() != 2) throw std::invalid_argument("lyapunov_spectrum: two scales (delta, delta_dot)");
    scale[0] = o.scale[0], scale[1] = o.scale[1];
  }
  if (!(scale[0] > 0) || !(scale[1] > 0)) throw std::invalid_argument("lyapunov_spectrum: scales must be > 0");
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

  kernel::Tangent t;
  t.xi[0] = scale[0], t.eta[1] = scale[1];  // unit vectors of the scaled state
  double d = lane.initial.deflection, v = lane.initial.velocity;
  double sum[2] = {0, 0};
  LyapunovSpectrum out;
  std::int64_t since = 0, counted = 0;
  std::size_t next_edge = 0;
  while (next_edge < edges.size() && edges[next_edge] == 0) {
    out.edges.push_back(SpectrumEdge{});
    ++next_edge;
  }
  for (std::int64_t n = 0; n < n_end; ++n) {
    kernel::rk4_step_tangent(mesh.plan(n), h, b, g.damping_coefficient, g.q3, lane.mu, lane.load, lane.load, d, v, t);
    if (!std::isfinite(d) || !std::isfinite(v))
      throw std::runtime_error("lyapunov_spectrum: the gear model diverged at t = " + std::to_string((n + 1) * h) + " s");
    if (d - mesh.transmission_error((n + 1) * h) <= b) out.last_separation = (n + 1) * h;
    ++since;
    const bool edge = next_edge < edges.size() && edges[next_edge] == n + 1;
    if (since == o.orthonormalise_every || edge || n + 1 == n_end) {
      double lr[2];
      orthonormalise(t, scale, lr);
      sum[0] += lr[0], sum[1] += lr[1];
      since = 0;
      ++counted;
      if (o.record_every > 0 && (counted % o.record_every == 0 || n + 1 == n_end)) {
        out.time.push_back((n + 1) * h);
        out.running.push_back(sum[0] / ((n + 1) * h));
      }
    }
    if (edge) {
      out.edges.push_back(SpectrumEdge{(n + 1) * h, {sum[0], sum[1]}, t.trace_integral});
      ++next_edge;
    }
  }
  const double T = n_end * h;
  out.exponent[0] = sum[0] / T;
  out.exponent[1] = sum[1] / T;
  out.trace = t.trace_integral / T;
  for (std::size_t k = 1; k < out.edges.size(); ++k) out.windows.push_back(window_between(out.edges[k - 1], out.edges[k]));
  return out;
}

SpectrumWindow window_between(const SpectrumEdge& from, const SpectrumEdge& to) {
  SpectrumWindow w;
  w.start = from.time;
  w.end = to.time;
  const double len = w.end - w.start;
  w.exponent[0] = (to.log_r[0] - from.log_r[0]) / len;
  w.exponent[1] = (to.log_r[1] - from.log_r[1]) / len;
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
