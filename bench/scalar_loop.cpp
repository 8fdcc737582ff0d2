#include "scalar_loop.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "gear_dynamics/engine/located_segment.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"

namespace gear_bench {

ScalarModel::ScalarModel(const gear_dynamics::GearPair& g, double time_step)
    : h_(time_step), b_(g.in.backlash), alpha_(g.damping_coefficient), q3_(g.q3), c0_(g.c0),
      c1_(g.c1), x_b_(g.x_b), rb1_(g.base_radius1), k1_(g.k1), k2_(g.k2), phase0_(g.in.mesh_phase),
      speed_(g.in.pinion_speed), period_(g.mesh_period_angle), single_(g.single_pair_angle) {
  // The split below handles one switch per step: the step's angle must be shorter than both
  // contact zones.
  if (speed_ * h_ >= std::fmin(single_, period_ - single_))
    throw std::invalid_argument("ScalarModel: a step spans more than one stiffness switch");
}

double ScalarModel::acceleration(double d, double v, double load, double K, double Q) const {
  double g = 0.0;  // penetration beyond the backlash
  if (d > b_) g = d - b_;
  if (d < -b_) g = d + b_;
  return load - Q * (K * g + alpha_ * std::fabs(g) * v);
}

// Classical RK4 over H with the load linear from la to lb; a step that may have met |d| = b (its
// stages' band, doc/model.md §5) is redone by the kernel's located segment.
void ScalarModel::rk4(double H, double la, double lb, double K, double qa, double qm, double qb,
                      double& d, double& v) const {
  const double d0 = d, v0 = v;
  const double lm = 0.5 * (la + lb);
  const double a1 = acceleration(d, v, la, K, qa);
  const double v2 = v + 0.5 * H * a1;
  const double a2 = acceleration(d + 0.5 * H * v, v2, lm, K, qm);
  const double v3 = v + 0.5 * H * a2;
  const double a3 = acceleration(d + 0.5 * H * v2, v3, lm, K, qm);
  const double v4 = v + H * a3;
  const double a4 = acceleration(d + H * v3, v4, lb, K, qb);
  d += H / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
  v += H / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
  const double reach = 0.25 * H * (std::fabs(v0) + std::fabs(v));
  const double lo = std::min({d0, d0 + 0.5 * H * v0, d0 + 0.5 * H * v2, d0 + H * v3, d}) - reach;
  const double hi = std::max({d0, d0 + 0.5 * H * v0, d0 + 0.5 * H * v2, d0 + H * v3, d}) + reach;
  if ((lo <= b_ && hi >= b_) || (lo <= -b_ && hi >= -b_)) {
    d = d0, v = v0;
    gear_dynamics::kernel::NoTangent none;
    gear_dynamics::kernel::located_segment({H, K, K, K, b_, alpha_, qa, qm, qb, la, lb, 0.0, 0.0}, d, v, none);
  }
}

void ScalarModel::step(std::int64_t n, double mu, double load0, double load1, double& d,
                       double& v) const {
  const double a0 = phase0_ + speed_ * (static_cast<double>(n) * h_);
  const double a1 = phase0_ + speed_ * (static_cast<double>(n + 1) * h_);
  // The next switch after a0; one within 1e-9 of a step of a grid point counts as on it.
  const double cycle = std::floor(a0 / period_);
  const double next = cycle * period_ + (a0 - cycle * period_ < single_ ? single_ : period_);
  const double tol = 1e-9 * (a1 - a0);
  if (next > a0 + tol && next < a1 - tol) {
    // Two sub-steps with K and Q frozen at their midpoints, the load interpolated at the switch.
    const double s = (next - a0) / (a1 - a0);
    const double load_s = load0 + s * (load1 - load0);
    for (const auto& [from, to, la, lb] :
         {std::array<double, 4>{a0, next, load0, load_s}, std::array<double, 4>{next, a1, load_s, load1}}) {
      const double mid = 0.5 * (from + to);
      const double local = mid - std::floor(mid / period_) * period_;
      const double q = q3_ + mu * friction(local);
      rk4((to - from) / (a1 - a0) * h_, la, lb, stiffness(local), q, q, q, d, v);
    }
    return;
  }
  // K from the midpoint; Q at the stage times, all measured in the midpoint's mesh cycle.
  const double mid = 0.5 * (a0 + a1);
  const double base = std::floor(mid / period_) * period_;
  rk4(h_, load0, load1, stiffness(mid - base), q3_ + mu * friction(a0 - base),
      q3_ + mu * friction(mid - base), q3_ + mu * friction(a1 - base), d, v);
}

ScalarState ScalarModel::run(const gear_dynamics::LaneSpec& lane, std::uint64_t seed, double delta0, double v0,
                             std::int64_t steps, std::int64_t every,
                             std::vector<ScalarState>* samples) const {
  const gear_dynamics::NormalStream stream(seed, lane.realization);
  constexpr std::size_t kChunk = 256;
  double z[kChunk] = {};
  const double sqrt_h = std::sqrt(h_);
  double d = delta0, v = v0;
  // Normal 0 gives Phi(0), normal n + 1 drives step n (doc/model.md §4).
  double load = lane.load_mean + (lane.stochastic ? lane.load_sd * stream.at(0) : 0.0);
  if (samples && every > 0) samples->push_back({d, v, load});
  for (std::int64_t n = 0; n < steps; ++n) {
    const auto k = static_cast<std::size_t>(n) % kChunk;
    if (lane.stochastic && k == 0) stream.fill(1 + static_cast<std::uint64_t>(n), z, kChunk);
    const double next = load + lane.drift * h_ + lane.sigma * sqrt_h * z[k];
    step(n, lane.mu, load, next, d, v);
    load = next;
    if (samples && every > 0 && (n + 1) % every == 0) samples->push_back({d, v, load});
  }
  return {d, v, load};
}

}  // namespace gear_bench
