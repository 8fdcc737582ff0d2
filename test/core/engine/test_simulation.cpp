// The analytic checks of doc/model.md §7, run through the production integrator (Ensemble), and
// simulate()'s observers against the full path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/engine/simulation.hpp"

namespace gd = gear_dynamics;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kLoad = 20.0;  // Phi0 [m/s^2]

struct Mesh {
  bool frozen = true;       // Omega = 0
  bool double_pair = false; // frozen in the double-contact zone (K = k2)
  bool damped = true;       // alpha from damping_ratio, else alpha = 0
  double backlash = 5e-5;
};

gd::GearPair gear(const Mesh& m) {
  gd::GearInputs in;
  if (m.frozen) in.pinion_speed = 0.0;
  if (m.double_pair) in.mesh_phase = 0.2;  // phi_m = 0.097 < 0.2 < phi_n = 0.314
  if (!m.damped) in.damping_ratio = 0.0;
  in.backlash = m.backlash;
  return gd::derive(in);
}

// One deterministic lane under a constant load.
gd::Ensemble single(const gd::GearPair& g, double h, double mu, double load, double d0, double v0) {
  gd::LaneSpec s;
  s.mu = mu;
  s.load_mean = load;
  s.stochastic = false;
  return gd::Ensemble(g, h, {d0, v0}, {s}, 1);
}

double q_frozen(const gd::GearPair& g, double mu) { return g.q3 + mu * g.friction_factor(g.in.mesh_phase); }

}  // namespace

// Check 1: free flight inside the backlash is exact; first contact at t_c = sqrt(2 b / Phi0).
TEST(Analytic, FreeFlight) {
  const gd::GearPair g = gear({});
  gd::Ensemble e = single(g, 1e-6, 0.0, kLoad, 0.0, 0.0);
  // RK4 integrates delta'' = Phi0 exactly; what remains is one rounding per step.
  for (int n = 1; n <= 2236; ++n) {
    e.step();
    const double t = e.time(), eps = n * 2.3e-16;
    ASSERT_NEAR(e.delta()[0], 0.5 * kLoad * t * t, eps * 0.5 * kLoad * t * t) << "n = " << n;
    ASSERT_NEAR(e.velocity()[0], kLoad * t, eps * kLoad * t) << "n = " << n;
  }
  const double tc = std::sqrt(2.0 * g.in.backlash / kLoad);
  EXPECT_NEAR(tc, 2.2360680e-3, 5e-11);
  EXPECT_NEAR(std::sqrt(2.0 * kLoad * g.in.backlash), 44.721360e-3, 5e-10);
  EXPECT_LT(e.delta()[0], g.in.backlash);  // t = 2.236 ms < t_c
  e.step();
  EXPECT_GT(e.delta()[0], g.in.backlash);  // t = 2.237 ms > t_c
}

// Check 2: static equilibrium under friction stays put to 1e-16 m.
TEST(Analytic, StaticEquilibrium) {
  const gd::GearPair g = gear({});
  const double mu = 0.03, q = q_frozen(g, mu);
  EXPECT_NEAR(q, 19.315703, 5e-7);
  const double eq = g.in.backlash + kLoad / (q * g.k1);
  gd::Ensemble e = single(g, 1e-6, mu, kLoad, eq, 0.0);
  for (int n = 0; n < 10000; ++n) {
    e.step();
    ASSERT_NEAR(e.delta()[0], eq, 1e-16) << "t = " << e.time();
  }
}

// Check 3: undamped oscillation about the equilibrium in contact, omega = sqrt(Q K).
TEST(Analytic, UndampedOscillationInContact) {
  for (const bool double_pair : {false, true}) {
    const gd::GearPair g = gear({true, double_pair, false});
    const double mu = 0.03, q = q_frozen(g, mu), k = double_pair ? g.k2 : g.k1;
    const double xs = kLoad / (q * k), eq = g.in.backlash + xs, amp = 0.5 * xs;
    const double w = std::sqrt(q * k);
    gd::Ensemble e = single(g, 1e-6, mu, kLoad, eq + amp, 0.0);
    double worst = 0.0;
    while (e.step_index() < 1000) {
      e.step();
      worst = std::max(worst, std::abs(e.delta()[0] - (eq + amp * std::cos(w * e.time()))));
    }
    EXPECT_LE(worst, 1e-3 * amp) << (double_pair ? "k2" : "k1");
  }
}

// Check 4: linear oscillator without backlash from rest, delta = x_s (1 - cos omega1 t).
TEST(Analytic, LinearOscillatorWithoutBacklash) {
  const gd::GearPair g = gear({true, false, false, 0.0});
  const double xs = kLoad / (g.q3 * g.k1), w = std::sqrt(g.q3 * g.k1);
  gd::Ensemble e = single(g, 1e-6, 0.0, kLoad, 0.0, 0.0);
  double worst = 0.0;
  while (e.step_index() < 1000) {
    e.step();
    worst = std::max(worst, std::abs(e.delta()[0] - xs * (1.0 - std::cos(w * e.time()))));
  }
  EXPECT_LE(worst, 1e-3 * xs);
}

namespace {

struct ImpactErrors {
  double energy;    // relative error of 1/2 v^2 - Phi0 (delta - b) after the contact
  double position;  // |delta - exact| 1 ms after the contact ended [m]
};

// Check 5 at step h: elastic impact from rest at delta = 0. The run starts `lead` seconds into
// the free flight (delta = Phi0 lead^2 / 2), which shifts where the boundary crossings fall
// within a step without changing the exact solution (the system is autonomous).
ImpactErrors elastic_impact(bool double_pair, double h, double lead) {
  const gd::GearPair g = gear({true, double_pair, false});
  const double b = g.in.backlash, k = double_pair ? g.k2 : g.k1;
  const double w = std::sqrt(g.q3 * k), xs = kLoad / (g.q3 * k);
  const double vc = std::sqrt(2.0 * kLoad * b), tc = std::sqrt(2.0 * b / kLoad);
  const double tk = (2.0 * kPi - 2.0 * std::atan(vc / (w * xs))) / w;
  gd::Ensemble e = single(g, h, 0.0, kLoad, 0.5 * kLoad * lead * lead, kLoad * lead);
  const auto steps = static_cast<std::int64_t>(std::llround((tc + tk + 1e-3 - lead) / h));
  while (e.step_index() < steps) e.step();
  const double s = e.time() + lead - (tc + tk);
  const double exact = b - vc * s + 0.5 * kLoad * s * s;
  const double energy = 0.5 * e.velocity()[0] * e.velocity()[0] - kLoad * (e.delta()[0] - b);
  return {std::abs(energy - kLoad * b) / (kLoad * b), std::abs(e.delta()[0] - exact)};
}

// A boundary crossing costs an O(h^2) velocity error whose constant depends on where in the step
// the crossing falls, and the entry and exit errors of one contact can cancel by accident when
// the contact lasts nearly a whole number of steps (t_k = 47.004 h for k2 at h = 1 us). The order is
// therefore measured on the mean error over 16 runs that spread both crossings across the step:
// the entry through the start offset, the exit through step sizes h (1 + j/128).
ImpactErrors phase_averaged(const std::function<ImpactErrors(double h, double lead)>& run, double h) {
  ImpactErrors sum{0.0, 0.0};
  for (int j = 0; j < 16; ++j) {
    const double hj = h * (1.0 + j / 128.0);
    const ImpactErrors e = run(hj, hj * ((5 * j) % 16) / 16.0);
    sum.energy += e.energy / 16.0;
    sum.position += e.position / 16.0;
  }
  return sum;
}

}  // namespace

// Check 5: the elastic impact conserves energy and lasts t_k; errors shrink >= 4x when h / 4.
TEST(Analytic, ElasticImpact) {
  const gd::GearPair g = gear({});
  for (const bool double_pair : {false, true}) {
    const double k = double_pair ? g.k2 : g.k1;
    const double w = std::sqrt(g.q3 * k), xs = kLoad / (g.q3 * k);
    const double vc = std::sqrt(2.0 * kLoad * g.in.backlash);
    const double tk = (2.0 * kPi - 2.0 * std::atan(vc / (w * xs))) / w;
    EXPECT_NEAR(tk, double_pair ? 47.00436e-6 : 62.26572e-6, 5e-12);

    // doc/model.md's case as stated: from rest at delta = 0, h = 1 us.
    const ImpactErrors stated = elastic_impact(double_pair, 1e-6, 0.0);
    EXPECT_LE(stated.energy, 1e-4);
    EXPECT_LE(stated.position, 2e-9);

    const auto run = [&](double h) {
      return phase_averaged([&](double hj, double lead) { return elastic_impact(double_pair, hj, lead); }, h);
    };
    const ImpactErrors coarse = run(1e-6), fine = run(0.25e-6);
    EXPECT_GE(coarse.energy / fine.energy, 4.0);
    EXPECT_GE(coarse.position / fine.position, 4.0);
    std::printf("[ order    ] check 5 (%s): mean energy error %.3e -> %.3e (order %.2f), mean position error %.3e -> %.3e m (order %.2f)\n",
                double_pair ? "k2" : "k1", coarse.energy, fine.energy,
                std::log(coarse.energy / fine.energy) / std::log(4.0), coarse.position, fine.position,
                std::log(coarse.position / fine.position) / std::log(4.0));
  }
}

namespace {

// Exact Hunt-Crossley rebound speed: v_in + v_out = ln[(1 + beta v_in) / (1 - beta v_out)] / beta.
double exact_rebound(double beta, double v_in) {
  double v = v_in;  // Newton from the elastic guess
  for (int i = 0; i < 50; ++i) {
    const double f = v_in + v - std::log((1.0 + beta * v_in) / (1.0 - beta * v)) / beta;
    const double df = 1.0 - 1.0 / (1.0 - beta * v);
    v -= f / df;
  }
  return v;
}

// Rebound speed at step h; the run starts `lead` seconds of free flight before the contact.
double rebound(double h, double v_in, double lead) {
  const gd::GearPair g = gear({});
  // Phi = 0; mu = 0.03 to show that Q drops out.
  gd::Ensemble e = single(g, h, 0.03, 0.0, g.in.backlash - v_in * lead, v_in);
  while (!(e.delta()[0] < g.in.backlash && e.velocity()[0] < 0.0)) e.step();
  e.step();  // free flight at constant speed once out of contact
  return -e.velocity()[0];
}

}  // namespace

// Check 6: Hunt-Crossley restitution; converges when h / 4.
TEST(Analytic, HuntCrossleyRestitution) {
  const gd::GearPair g = gear({});
  const double beta = g.damping_coefficient / g.k1;
  // doc/model.md prints 0.8926607; its own alpha / k1 = 1.2003894e8 / 1.3447321e8 = 0.89266063.
  EXPECT_NEAR(beta, 0.8926607, 1e-6 * beta);
  const double v_in = 0.05, exact = exact_rebound(beta, v_in);
  EXPECT_NEAR(exact, 0.04855510, 5e-9);
  EXPECT_LE(std::abs(rebound(1e-6, v_in, 0.0) - exact) / exact, 5e-5);  // doc/model.md's case

  const auto mean_error = [&](double h) {
    return phase_averaged(
               [&](double hj, double lead) {
                 return ImpactErrors{std::abs(rebound(hj, v_in, lead) - exact) / exact, 0.0};
               },
               h)
        .energy;
  };
  const double coarse = mean_error(1e-6), fine = mean_error(0.25e-6);
  EXPECT_GE(coarse / fine, 4.0);
  std::printf("[ order    ] check 6: mean relative error %.3e -> %.3e (order %.2f)\n", coarse, fine,
              std::log(coarse / fine) / std::log(4.0));
  // Small beta v: 1 - e ~ (2/3) beta v.
  const double v_small = 1e-3;
  EXPECT_NEAR(1.0 - exact_rebound(beta, v_small) / v_small, 2.0 / 3.0 * beta * v_small, 1e-3 * beta * v_small);
}

// Check 7: the load process. E[Phi(t)] = Phi0 + lambda t, Cov(Phi(s), Phi(t)) = sd0^2 + sigma^2 min(s, t),
// increments N(lambda h, sigma^2 h); sample moments over 1e4 paths within 4 standard errors.
TEST(Analytic, LoadProcessMoments) {
  const gd::GearPair g = gear({});
  const int paths = 10000;
  // sigma^2 t must stand well above the sampling error of sd0^2, hence a large sigma and small sd0.
  const double mean0 = 20.0, sd0 = 1.0, sigma = 50.0, drift = 400.0, h = 1e-6;
  std::vector<gd::LaneSpec> lanes(paths);
  for (int r = 0; r < paths; ++r) {
    lanes[r].load_mean = mean0;
    lanes[r].load_sd = sd0;
    lanes[r].sigma = sigma;
    lanes[r].drift = drift;
    lanes[r].realization = r;
  }
  gd::Ensemble e(g, h, {}, lanes, 7);
  const Eigen::ArrayXd phi0 = e.load();
  e.step();
  const Eigen::ArrayXd inc = e.load() - phi0;
  const std::int64_t ns = 2000, nt = 5000;  // s = 2 ms, t = 5 ms
  while (e.step_index() < ns) e.step();
  const Eigen::ArrayXd phis = e.load();
  while (e.step_index() < nt) e.step();
  const Eigen::ArrayXd phit = e.load();

  const auto mean = [](const Eigen::ArrayXd& x) { return x.mean(); };
  const auto var = [&](const Eigen::ArrayXd& x) { return (x - mean(x)).square().sum() / (x.size() - 1); };
  const double n = paths;
  const auto check_mean = [&](const Eigen::ArrayXd& x, double m, double v, const char* what) {
    EXPECT_NEAR(mean(x), m, 4.0 * std::sqrt(v / n)) << what;
  };
  const auto check_var = [&](const Eigen::ArrayXd& x, double v, const char* what) {
    EXPECT_NEAR(var(x), v, 4.0 * v * std::sqrt(2.0 / (n - 1))) << what;
  };
  const double s = ns * h, t = nt * h;
  check_mean(phi0, mean0, sd0 * sd0, "Phi(0)");
  check_var(phi0, sd0 * sd0, "Phi(0)");
  check_mean(inc, drift * h, sigma * sigma * h, "increment");
  check_var(inc, sigma * sigma * h, "increment");
  check_mean(phis, mean0 + drift * s, sd0 * sd0 + sigma * sigma * s, "Phi(s)");
  check_var(phis, sd0 * sd0 + sigma * sigma * s, "Phi(s)");
  check_mean(phit, mean0 + drift * t, sd0 * sd0 + sigma * sigma * t, "Phi(t)");
  check_var(phit, sd0 * sd0 + sigma * sigma * t, "Phi(t)");
  // Covariance: the standard error of a sample covariance of jointly normal (X, Y) is
  // sqrt((var X var Y + cov^2) / n).
  const double cov_exact = sd0 * sd0 + sigma * sigma * s;
  const double cov = ((phis - mean(phis)) * (phit - mean(phit))).sum() / (n - 1);
  const double vs = sd0 * sd0 + sigma * sigma * s, vt = sd0 * sd0 + sigma * sigma * t;
  EXPECT_NEAR(cov, cov_exact, 4.0 * std::sqrt((vs * vt + cov_exact * cov_exact) / n));
  // At T = 0.4 s with the paper's sd0 = 5, sigma = 5 (doc/model.md): sd 5.9160798 m/s^2.
  EXPECT_NEAR(std::sqrt(5.0 * 5.0 + 5.0 * 5.0 * 0.4), 5.9160798, 5e-8);
}

// Check 8: natural frequencies, measured as the period of the oscillator of check 4, on both
// stiffness levels and with friction (omega = sqrt(Q K)).
TEST(Analytic, NaturalFrequencies) {
  for (const double mu : {0.0, 0.05}) {
    for (const bool double_pair : {false, true}) {
      const gd::GearPair g = gear({true, double_pair, false, 0.0});
      const double k = double_pair ? g.k2 : g.k1;
      const double w = std::sqrt(q_frozen(g, mu) * k);
      if (mu == 0.0) {
        EXPECT_NEAR(w, double_pair ? 67119.69 : 50737.72, 1e-2);
      }
      // delta = x_s (1 - cos w t) comes back to 0 at t = 2 pi / w: locate the minimum.
      const double h = 1e-7;
      gd::Ensemble e = single(g, h, mu, kLoad, 0.0, 0.0);
      double prev_v = 0.0, t_min = 0.0;
      while (e.time() < 1.5 * 2.0 * kPi / w) {
        e.step();
        const double v = e.velocity()[0];
        if (e.time() > kPi / w && prev_v < 0.0 && v >= 0.0) t_min = e.time() - h * v / (v - prev_v);
        prev_v = v;
      }
      EXPECT_NEAR(2.0 * kPi / t_min, w, 1e-5 * w) << "mu " << mu << (double_pair ? " k2" : " k1");
    }
  }
}

// The deterministic reference run S1: finishes, stays finite, and the analysis values are sane.
TEST(Analytic, DeterministicRunS1Finishes) {
  gd::GearInputs in;
  const gd::GearPair g = gd::derive(in);
  gd::LaneSpec s1;
  s1.mu = 0.04;
  s1.stochastic = false;
  gd::Ensemble e(g, 1e-6, {}, {s1}, 1);
  gd::RunSettings run;
  run.duration = 0.05;
  run.window = 0.01;
  run.snapshot_times = {0.01, 0.05};
  const auto r = gd::simulate(e, run);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_TRUE(std::isfinite(r[0].center_distance));
  EXPECT_GT(r[0].center_distance, 0.0);
  EXPECT_GT(r[0].steady_state_time, 0.0);  // the start-up transient is still on at 50 ms
  ASSERT_EQ(r[0].snapshots.size(), 2u);
  EXPECT_EQ(r[0].snapshots[1].delta, r[0].final_delta);
  EXPECT_EQ(r[0].final_load, 20.0);
}

namespace {

// The exact undamped contact oscillation about delta_eq = b + x_s with amplitude A > x_s: it leaves
// contact where x = delta - delta_eq = -x_s, flies free under Phi0 back to b, and re-enters; one
// period is 2 t1 + t_free, started at the top turning point x = A.
double grazing_exact(double t, double b, double xs, double w, double A) {
  const double t1 = std::acos(-xs / A) / w;  // top to leaving contact
  const double v1 = A * w * std::sin(w * t1);  // speed away from b when leaving
  const double tf = 2.0 * v1 / kLoad;
  const double period = 2.0 * t1 + tf;
  double s = std::fmod(t, period);
  if (s <= t1) return b + xs + A * std::cos(w * s);
  s -= t1;
  if (s <= tf) return b - v1 * s + 0.5 * kLoad * s * s;
  s -= tf;  // back in contact, rising from x = -x_s to the top
  return b + xs + A * std::cos(w * (s - t1));
}

}  // namespace

// A grazing contact: the undamped oscillation in contact (frozen mesh, K = k1) with an amplitude
// 1e-4 above x_s leaves contact for 0.6 us per period, inside one step, both ends of the step in
// contact. The located scheme finds each excursion on the step's dense output; its error over 2 ms
// (16 excursions) falls like h^4.
TEST(Analytic, GrazingContactConvergesAtOrderFour) {
  const gd::GearPair g = gear({true, false, false});
  const double b = g.in.backlash, xs = kLoad / (g.q3 * g.k1), w = std::sqrt(g.q3 * g.k1);
  const double A = xs * (1.0 + 1e-4), T = 2e-3;
  const auto error = [&](double h) {
    gd::Ensemble e = single(g, h, 0.0, kLoad, b + xs + A, 0.0);
    while (e.step_index() < std::llround(T / h)) e.step();
    return std::abs(e.delta()[0] - grazing_exact(e.time(), b, xs, w, A)) / xs;
  };
  const double e4 = error(4e-6), e2 = error(2e-6), e1 = error(1e-6);
  std::printf("[ order    ] grazing contact: |delta - exact| / x_s %.3e, %.3e, %.3e at h = 4, 2, 1 us (orders %.2f, %.2f)\n",
              e4, e2, e1, std::log2(e4 / e2), std::log2(e2 / e1));
  EXPECT_LE(e2, 1e-3);
  EXPECT_GE(e4 / e2, 10.0);
  EXPECT_GE(e2 / e1, 10.0);
}

// The full model (mesh turning at the paper's speed, mu = 0.04, Hunt-Crossley damping) from rest to
// 20 ms: impacts, rebounds, and the mesh phase chosen so that a k1 -> k2 switch falls 30 us into
// the first contact (t_c = 2.236 ms). Without an exact solution the
// order shows in the differences of successive halvings, D(h) = |delta_h - delta_h/2|, whose ratio
// is 2^p: at least 10 (p > 3.3) per halving from 4 us down.
TEST(Analytic, FullModelConvergesAtOrderFour) {
  gd::GearInputs in;
  const gd::GearPair g0 = gd::derive(in);
  const double t_switch = std::sqrt(2.0 * g0.in.backlash / kLoad) + 30e-6;
  in.mesh_phase = std::fmod(g0.single_pair_angle - in.pinion_speed * t_switch + 10.0 * g0.mesh_period_angle,
                            g0.mesh_period_angle);
  const gd::GearPair g = gd::derive(in);
  const double T = 0.02;
  int switches_in_contact = 0;
  const auto run = [&](double h, bool count) {
    gd::Ensemble e = single(g, h, 0.04, kLoad, 0.0, 0.0);
    while (e.step_index() < std::llround(T / h)) {
      if (count && e.mesh().plan(e.step_index()).segments > 1 && std::abs(e.delta()[0]) > g.in.backlash)
        ++switches_in_contact;
      e.step();
    }
    return std::pair<double, double>(e.delta()[0], e.velocity()[0]);
  };
  std::vector<std::pair<double, double>> y;
  for (const double h : {4e-6, 2e-6, 1e-6, 0.5e-6, 0.25e-6}) y.push_back(run(h, h == 1e-6));
  EXPECT_GE(switches_in_contact, 1);
  std::vector<double> diff;
  for (std::size_t k = 0; k + 1 < y.size(); ++k) diff.push_back(std::abs(y[k].first - y[k + 1].first));
  std::printf("[ order    ] full model at 20 ms: D(h) = %.3e, %.3e, %.3e, %.3e m for h = 4, 2, 1, 0.5 us; "
              "%d switches in contact\n", diff[0], diff[1], diff[2], diff[3], switches_in_contact);
  for (std::size_t k = 0; k + 1 < diff.size(); ++k) EXPECT_GE(diff[k] / diff[k + 1], 10.0) << "halving " << k;
}

// simulate(): the window range at T and the snapshots equal a brute-force pass over the path.
TEST(Simulate, ObserversAgreeWithTheFullPath) {
  const gd::GearPair g = gd::derive(gd::GearInputs{});
  std::vector<gd::LaneSpec> lanes(3);
  for (int i = 0; i < 3; ++i) {
    lanes[i].mu = 0.02 * i;
    lanes[i].sigma = 5.0;
    lanes[i].load_sd = 5.0;
    lanes[i].realization = i;
  }
  gd::RunSettings run;
  run.time_step = 1e-6;
  run.duration = 0.02;
  run.window = 0.005;
  run.snapshot_times = {0.01, 0.017, 0.02};

  gd::Ensemble a(g, 1e-6, {}, lanes, 11);
  gd::Recorder rec;
  rec.every = 250;
  int records = 0;
  Eigen::ArrayXd d_live;
  rec.record = [&](const gd::Ensemble&, const Eigen::ArrayXd& d) {
    ++records;
    d_live = d;
  };
  const auto results = gd::simulate(a, run, rec);
  EXPECT_EQ(records, 20000 / 250 + 1);

  gd::Ensemble b(g, 1e-6, {}, lanes, 11);
  Eigen::ArrayXd dmax = Eigen::ArrayXd::Constant(3, -1e300), dmin = -dmax, vmax = dmax, vmin = -dmax;
  Eigen::ArrayXd last_out = Eigen::ArrayXd::Zero(3);
  std::vector<Eigen::ArrayXd> snap;
  const double b_lash = g.in.backlash;
  for (std::int64_t n = 0; n <= 20000; ++n) {
    if (n > 0) b.step();
    if (n >= 15000) {
      dmax = dmax.max(b.delta());
      dmin = dmin.min(b.delta());
      vmax = vmax.max(b.velocity());
      vmin = vmin.min(b.velocity());
    }
    for (int i = 0; i < 3; ++i)
      if (std::abs(b.delta()[i] - b_lash) > 0.1 * b_lash) last_out[i] = b.time();
    if (n == 10000 || n == 17000 || n == 20000) snap.push_back(b.delta());
  }
  for (int i = 0; i < 3; ++i) {
    const double d = std::sqrt((dmax[i] - dmin[i]) * (vmax[i] - vmin[i]));
    EXPECT_EQ(results[i].center_distance, d);
    EXPECT_EQ(d_live[i], d);  // the live d(T) over the trailing window is the same number
    EXPECT_EQ(results[i].steady_state_time, last_out[i]);
    EXPECT_EQ(results[i].reached_steady_state, std::llround(last_out[i] / 1e-6) < 20000);
    ASSERT_EQ(results[i].snapshots.size(), 3u);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(results[i].snapshots[k].delta, snap[k][i]);
    EXPECT_DOUBLE_EQ(results[i].snapshots[1].time, 0.017);
  }
}
