// The RK4 kernel's explicit fused multiply-adds (engine/rk4_kernel.hpp, doc/model.md §5): one step
// from many states against a plain evaluation of the same formulas (every product rounded before
// its sum, the unfused scheme), so a fusion of the wrong operands shows; and
// the packet instantiations (8 and 16 lanes: FMA instructions) bit for bit against the scalar one
// (std::fma).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gd = gear_dynamics;
namespace kernel = gear_dynamics::kernel;

namespace {

// Step n of a frozen mesh K with the transmission error e(t) = c t.
gd::StepPlan ramp(double K, double c, int n, double h) {
  gd::StepPlan p;
  p.excited = true;
  gd::StepSegment& s = p.segment[0];
  s.stiffness_start = s.stiffness_mid = s.stiffness_end = K;
  s.error_start = c * n * h, s.error_end = c * (n + 1) * h;
  return p;
}


gd::GearPair shipped_gear(double* time_step) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  const gd::ModelConfig c =
      gd::parse_config(gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
  *time_step = c.run.time_step;
  return derive(c.gear);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct State {
  double d, v, load0, load1, mu;
};

// The unfused step (each product rounded, then each sum) and the magnitudes a rounding error of
// the step scales with: of d, and of the velocity's increments H a, whose terms are the load and
// q K d (d's own rounding reaches the force through K, in contact) and q alpha |d v|.
struct Plain {
  double d, v;
  double d_scale = 0.0, v_scale = 0.0;
  bool near_boundary = false;  // a segment's stages may have met |d| = b: the kernel locates it instead
};

Plain plain_step(const gd::StepPlan& plan, double h, const gd::GearPair& g, const State& s) {
  const double b = g.in.backlash, alpha = g.damping_coefficient, q3 = g.q3;
  Plain r{s.d, s.v};
  double term_max = 0.0, v_max = std::fabs(s.v);
  for (int k = 0; k < plan.segments; ++k) {
    const gd::StepSegment& seg = plan.segment[k];
    const double H = (seg.end - seg.begin) * h, half = 0.5 * H;
    const double e_dot = (seg.error_end - seg.error_start) / H, em = 0.5 * (seg.error_start + seg.error_end);
    const double la = s.load0 + seg.begin * (s.load1 - s.load0), lb = s.load0 + seg.end * (s.load1 - s.load0);
    const double lm = 0.5 * (la + lb);
    const double qa = q3 + s.mu * seg.friction_start, qm = q3 + s.mu * seg.friction_mid,
                 qb = q3 + s.mu * seg.friction_end;
    const auto acc = [&](double d, double v, double load, double q, double K, double e) {
      const double gap = (d - e) - std::min(std::max(d - e, -b), b);
      const double contact = gap != 0.0 ? std::fabs(d) : 0.0;
      term_max = std::max(term_max, std::fabs(load) + q * (K * contact + alpha * contact * std::fabs(v)));
      v_max = std::max(v_max, std::fabs(v));
      return load - q * (K * gap + (alpha * std::fabs(gap)) * (v - e_dot));
    };
    double& d = r.d;
    double& v = r.v;
    const double d0 = d, v0 = v;
    const double a1 = acc(d, v, la, qa, seg.stiffness_start, seg.error_start);
    const double v2 = v + half * a1;
    const double a2 = acc(d + half * v, v2, lm, qm, seg.stiffness_mid, em);
    const double v3 = v + half * a2;
    const double a3 = acc(d + half * v2, v3, lm, qm, seg.stiffness_mid, em);
    const double v4 = v + H * a3;
    const double a4 = acc(d + H * v3, v4, lb, qb, seg.stiffness_end, seg.error_end);
    const double x[3] = {d0 + half * v0, d0 + half * v2, d0 + H * v3};
    d += (H / 6.0) * (v + 2.0 * v2 + 2.0 * v3 + v4);
    v += (H / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    // The band of doc/model.md §5 (with a little slack for the plain roundings).
    const double reach = 0.26 * H * (std::fabs(v0) + std::fabs(v));
    const double spread = std::fabs(seg.error_end - seg.error_start);
    const double lo = std::min({d0, x[0], x[1], x[2], d}) - reach - seg.error_start - spread,
                 hi = std::max({d0, x[0], x[1], x[2], d}) + reach - seg.error_start + spread;
    r.near_boundary = r.near_boundary || (lo <= b && hi >= b) || (lo <= -b && hi >= -b);
  }
  r.d_scale = std::max(std::fabs(s.d), std::fabs(r.d)) + h * v_max;
  r.v_scale = std::max(std::fabs(s.v), std::fabs(r.v)) + h * term_max;
  return r;
}

// Plans of the first mesh periods: unsplit steps and every split one among them.
std::vector<gd::StepPlan> some_plans(const gd::GearPair& g, double h) {
  const gd::MeshSchedule mesh(g, h);
  std::vector<gd::StepPlan> plans;
  int unsplit = 0;
  for (std::int64_t n = 0; n < 7000; ++n) {
    const gd::StepPlan p = mesh.plan(n);
    if (p.segments > 1 || (n % 97 == 0 && unsplit++ < 40)) plans.push_back(p);
  }
  return plans;
}

// States around the contacts on both flanks (|d| near b, where K d is many times the load), in
// free flight, at rest, and with the load rising or falling within the step.
std::vector<State> some_states(const gd::GearPair& g, int count) {
  const double b = g.in.backlash;
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<State> states;
  for (int i = 0; i < count; ++i) {
    State s{};
    const double side = unit(rng) < 0.0 ? -1.0 : 1.0;
    switch (i % 4) {
      case 0: s.d = side * (b + 5e-7 * (0.5 + unit(rng))); break;   // in contact (or just out)
      case 1: s.d = side * (b + 2e-8 * (1.0 + unit(rng))); break;   // near static deflection
      case 2: s.d = b * unit(rng); break;                           // free flight
      default: s.d = side * b; break;                               // on the boundary
    }
    s.v = i % 8 == 7 ? 0.0 : 0.05 * unit(rng) * (i % 3 == 0 ? 1e-6 : 1.0);
    s.load0 = 20.0 + 20.0 * unit(rng);
    s.load1 = s.load0 + 0.05 * unit(rng);
    s.mu = 0.1 + 0.1 * unit(rng);
    states.push_back(s);
  }
  return states;
}

}  // namespace

// The fused step differs from the plain one only by where roundings fall: each fusion removes the
// rounding of one product (at most half an ulp of it) and each moved rounding errs by at most half
// an ulp of its sum, and a stage's error reaches (d, v) weighted by at most H: so the two differ by
// a few eps of d (its last sum) and of v plus H times the stages' force terms (of which d's own
// rounding in a stage argument is the largest in contact: q K ulp(d)). 4 eps of those scales
// (measured: at most about 1.5) fails for any fusion of the wrong operands, which errs at order 1.
// Steps that may meet a backlash boundary go through the located segment instead (test_analytic's
// order checks); they are left out here.
TEST(RK4Kernel, FusedStepAgreesWithPlainEvaluation) {
  double h = 0.0;
  const gd::GearPair g = shipped_gear(&h);
  const double eps = std::numeric_limits<double>::epsilon();
  double worst_d = 0.0, worst_v = 0.0;
  int compared = 0;
  for (const gd::StepPlan& plan : some_plans(g, h)) {
    for (const State& s : some_states(g, 400)) {
      double d = s.d, v = s.v;
      kernel::rk4_step<double>(plan, h, g.in.backlash, g.damping_coefficient, g.q3, s.mu, s.load0, s.load1, d, v);
      const Plain p = plain_step(plan, h, g, s);
      if (p.near_boundary) continue;
      const double err_d = std::fabs(d - p.d) / (eps * p.d_scale), err_v = std::fabs(v - p.v) / (eps * p.v_scale);
      worst_d = std::max(worst_d, err_d);
      worst_v = std::max(worst_v, err_v);
      ASSERT_LE(err_d, 4.0) << "d " << s.d << " v " << s.v << " segments " << plan.segments << ": " << d << " vs "
                            << p.d;
      ASSERT_LE(err_v, 4.0) << "d " << s.d << " v " << s.v << " segments " << plan.segments << ": " << v << " vs "
                            << p.v;
      ++compared;
    }
  }
  EXPECT_GT(compared, 10000);
  std::printf("fused vs plain RK4 step over %d states: at most %.2f eps of d's scale, %.2f eps of v's\n", compared,
              worst_d, worst_v);
}

// The load update likewise: Phi0 + lambda h + (sigma sqrt(h)) z against the plain sums.
TEST(RK4Kernel, FusedLoadUpdateAgreesWithPlainEvaluation) {
  const double h = 1e-6, sqrt_h = std::sqrt(h), eps = std::numeric_limits<double>::epsilon();
  std::mt19937_64 rng(19);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 10000; ++i) {
    const double load0 = 20.0 + 5.0 * normal(rng), drift = 1e3 * normal(rng), sigma = 50.0 * std::fabs(normal(rng));
    const double z = normal(rng);
    const double fused = kernel::load_next<double>(load0, drift, sigma, z, h, sqrt_h);
    const double plain = load0 + drift * h + (sigma * sqrt_h) * z;
    // Two roundings moved, each at most half an ulp of the sums' magnitudes.
    ASSERT_LE(std::fabs(fused - plain), 2.0 * eps * (std::fabs(load0) + std::fabs(drift * h) + std::fabs(sigma * sqrt_h * z)));
  }
}

// The packets' FMA instructions and the scalar std::fma give the same bits lane by lane (the
// Realization / Ensemble identity of test_realization.cpp, here from states a run may not reach:
// signed zeros, boundaries, split steps).
template <int N>
void expect_packet_equals_scalar() {
  double h = 0.0;
  const gd::GearPair g = shipped_gear(&h);
  const std::vector<State> states = some_states(g, 8 * N);
  for (const gd::StepPlan& plan : some_plans(g, h)) {
    for (std::size_t first = 0; first + N <= states.size(); first += N) {
      kernel::Lanes<N> d, v, load0, load1, mu, drift, sigma, z;
      for (int i = 0; i < N; ++i) {
        const State& s = states[first + i];
        d[i] = s.d;
        v[i] = s.v;
        load0[i] = s.load0;
        load1[i] = s.load1;
        mu[i] = s.mu;
        drift[i] = 1e3 * (i - 3);
        sigma[i] = 10.0 * i;
        z[i] = i % 5 == 0 ? -0.0 : 0.3 * (i - 7);
      }
      const kernel::Lanes<N> next = kernel::load_next<kernel::Lanes<N>>(load0, drift, sigma, z, h, std::sqrt(h));
      kernel::rk4_step<kernel::Lanes<N>>(plan, h, g.in.backlash, g.damping_coefficient, g.q3, mu, load0, load1, d, v);
      for (int i = 0; i < N; ++i) {
        const State& s = states[first + i];
        double ds = s.d, vs = s.v;
        kernel::rk4_step<double>(plan, h, g.in.backlash, g.damping_coefficient, g.q3, s.mu, s.load0, s.load1, ds, vs);
        const double next_s = kernel::load_next<double>(s.load0, drift[i], sigma[i], z[i], h, std::sqrt(h));
        ASSERT_TRUE(same_bits(d[i], ds) && same_bits(v[i], vs) && same_bits(next[i], next_s))
            << "lane " << i << " of " << N << ": " << d[i] << " vs " << ds << ", " << v[i] << " vs " << vs;
      }
    }
  }
}

TEST(RK4Kernel, PacketsOf8EqualScalarBitForBit) { expect_packet_equals_scalar<8>(); }
TEST(RK4Kernel, PacketsOf16EqualScalarBitForBit) { expect_packet_equals_scalar<16>(); }

// The kernel with a transmission error (profile errors, doc/model.md §5).

// Every profile error the same: e is that constant, and the motion is the paper's shifted by it
// (the boundaries and the spring move together), to rounding over the first 20 ms.
TEST(RK4Kernel, EqualProfileErrorsShiftTheMotion) {
  gd::GearInputs in;
  const double c = 3e-6;
  in.profile_errors.pinion.assign(in.pinion_teeth, c);
  const gd::GearPair g0 = gd::derive(gd::GearInputs{}), g1 = gd::derive(in);
  const double h = 2.5e-6;
  gd::Ensemble a(g0, h, {0.0, 0.0}, {gd::LaneSpec{0.04, 0.0, 0.0, 20.0, 0.0, 0, false}}, 1);
  gd::Ensemble b(g1, h, {c, 0.0}, {gd::LaneSpec{0.04, 0.0, 0.0, 20.0, 0.0, 0, false}}, 1);
  EXPECT_NE(b.mesh().table(), nullptr);
  double worst = 0.0;
  for (int n = 0; n < 8000; ++n) {
    a.step(), b.step();
    worst = std::max(worst, std::abs(b.delta()[0] - c - a.delta()[0]));
  }
  EXPECT_LT(worst, 1e-12) << "largest |delta_e - e - delta_0| [m]";
}

// The kernel with e(t) = c t in permanent contact without backlash or damping (b = 0, alpha = 0,
// frozen K): delta = F/(qK) (1 - cos wt) + c (t - sin(wt)/w) from rest. RK4's error shrinks as h^4.
TEST(RK4Kernel, FollowsALinearTransmissionError) {
  const double K = 1.3447321e8, q = 19.143710, F = 20.0, c = 1e-3, w = std::sqrt(q * K);
  const auto run = [&](double h) {
    double d = 0.0, v = 0.0, worst = 0.0;
    const int N = static_cast<int>(std::round(1e-3 / h));
    for (int n = 0; n < N; ++n) {
      gd::kernel::rk4_step<double>(ramp(K, c, n, h), h, 0.0, 0.0, q, 0.0, F, F, d, v);
      const double t = (n + 1) * h;
      worst = std::max(worst, std::abs(d - (F / (q * K) * (1 - std::cos(w * t)) + c * (t - std::sin(w * t) / w))));
    }
    return worst;
  };
  const double scale = F / (q * K) + c / w, e1 = run(1e-6), e2 = run(0.5e-6);
  EXPECT_LT(e1, 1e-3 * scale);
  EXPECT_GT(e1 / e2, 12.0) << e1 << " " << e2;
}

// A boundary that moves (b + c t) is located: free flight, impact, rebound; the state at 3.2 ms,
// after them, converges at fourth order (its error against h/16 shrinks >= 10x per halving).
TEST(RK4Kernel, LocatesAMovingBoundary) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  const double K = g.k1, q = g.q3, b = g.in.backlash, alpha = g.damping_coefficient, F = 20.0, c = -4e-3;
  const auto run = [&](double h) {
    double d = 0.0, v = 0.0;
    const int N = static_cast<int>(std::round(3.2e-3 / h));
    for (int n = 0; n < N; ++n) {
      gd::kernel::rk4_step<double>(ramp(K, c, n, h), h, b, alpha, q, 0.0, F, F, d, v);
    }
    return d;
  };
  const double ref = run(0.125e-6), e1 = std::abs(run(2e-6) - ref), e2 = std::abs(run(1e-6) - ref),
               e3 = std::abs(run(0.5e-6) - ref);
  EXPECT_GT(e1 / e2, 10.0) << e1 << " " << e2;
  EXPECT_GT(e2 / e3, 10.0) << e2 << " " << e3;
}

// The reported mesh force of a gear with profile errors is the force the kernel damps with:
// K g(delta - e) + alpha |g| (delta_dot - e_dot). Independently: e_dot as a forward difference of
// e(t) over 1 ns (inside one node of the table, where e is a straight line, so only rounding
// differs), and the force as -acceleration of the kernel at the state with load 0 and Q = 1.
TEST(RK4Kernel, MeshForceIsTheForceTheKernelDamps) {
  gd::GearInputs in;
  in.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;  // shares vary: e varies within a piece
  in.profile_errors.pinion = {4e-6, -3e-6, 0.0, 5e-6, -2e-6};
  in.profile_errors.wheel = {1e-6, 0.0, -4e-6};
  const gd::GearPair g = gd::derive(in);
  const double h = 2.5e-6, dt = 1e-9;
  gd::Ensemble e(g, h, {g.in.backlash + 2e-6, 0.0}, {gd::LaneSpec{0.04, 0.0, 0.0, 2000.0, 0.0, 0, false}}, 1);
  int compared = 0, moving = 0;
  double worst_rate = 0.0, worst_force = 0.0, largest_change = 0.0;
  for (int n = 0; n < 40000; ++n) {
    e.step();
    if (n % 7 != 0) continue;
    const double t = e.time(), K = e.mesh().stiffness(t), err = e.mesh().transmission_error(t);
    const double rate = e.mesh().transmission_error_rate(t);
    const double fd = (e.mesh().transmission_error(t + dt) - err) / dt;
    const double d = e.delta()[0], v = e.velocity()[0];
    const double force = gd::mesh_force(g, K, d, v, err, rate);
    const double kernel = -gd::kernel::acceleration<double, double, true>(d, v, 0.0, K, 1.0, g.in.backlash,
                                                                       g.damping_coefficient, err, fd);
    // e ~ 1e-5 m over 1 ns: rounding of the difference ~ 1e-21 / 1e-9 = 1e-12 m/s; 1e-9 m/s allows
    // a node boundary inside the nanosecond on a few samples, which the count below would show.
    if (std::abs(rate - fd) > 1e-9) continue;
    ++compared;
    worst_rate = std::max(worst_rate, std::abs(rate - fd));
    // Relative to the force scale K b: the two differ only by the fused roundings of the kernel.
    worst_force = std::max(worst_force, std::abs(force - kernel) / (K * g.in.backlash));
    if (rate != 0.0) ++moving;
    largest_change = std::max(largest_change, std::abs(force - gd::mesh_force(g, K, d, v, err, 0.0)));
  }
  EXPECT_GT(compared, 5000) << "samples with the same slope on both sides of 1 ns";
  // e moves only where two pairs share the load with changing shares (a quarter of the samples here).
  EXPECT_GT(moving, compared / 10) << "samples where e moves";
  EXPECT_LT(worst_force, 1e-12);
  // The damper's e_dot term matters: without it the force differs by more than 1 mN somewhere.
  EXPECT_GT(largest_change, 1e-3) << "largest |F(e_dot) - F(0)| [N]";
  std::printf("%d samples, %d with e moving; largest |e_dot - fd| %.1e m/s, |F(e_dot) - F(0)| %.3e N\n",
              compared, moving, worst_rate, largest_change);
}
