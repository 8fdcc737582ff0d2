// The condition indicators, the time-synchronous average and the revolution windows against closed
// forms on analytic signals (doc/monitor.md §7).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "gear_dynamics/monitor/indicators.hpp"

namespace gd = gear_dynamics;

namespace {

constexpr double kTwoPi = 6.283185307179586;

gd::IndicatorSettings settings() {
  gd::IndicatorSettings s;
  s.teeth = 20;
  s.samples_per_revolution = 640;
  return s;
}

// A TSA-length signal f(theta) on the grid theta_i = 2 pi i / N.
template <class F>
Eigen::VectorXd on_grid(int n, F f) {
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x(i) = f(kTwoPi * i / n);
  return x;
}

double value(const std::vector<double>& v, const char* name) { return v[gd::indicator_index(name)]; }

// The time-synchronous average's test signal: a few incommensurate tones.
double periodic(double t) { return std::cos(20 * t) + 0.3 * std::sin(3 * t + 0.2) + 0.05 * std::cos(41 * t); }

}  // namespace

TEST(MonitorIndicators, TableNamesAreUniqueAndComplete) {
  const auto names = gd::indicator_names();
  for (const char* n : {"rms", "kurtosis", "crest_factor", "fm0", "fm4", "m6a", "m8a", "na4", "na4_star", "nb4",
                        "energy_ratio", "sideband_level", "sideband_index"})
    EXPECT_NO_THROW(gd::indicator_index(n)) << n;
  for (std::size_t i = 0; i < names.size(); ++i)
    for (std::size_t j = i + 1; j < names.size(); ++j) EXPECT_NE(names[i], names[j]);
  try {
    gd::indicator_index("fm5");
    FAIL() << "an unknown name was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'fm5'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fm4"), std::string::npos) << e.what();
  }
}

// A sine's moments over whole periods are exact: kurtosis 3/2, RMS A/sqrt 2, crest factor sqrt 2
// (the grid holds the peaks: N is a multiple of 4 per period); rounding only, hence 1e-12.
TEST(MonitorIndicators, SineKurtosisRmsCrestFactor) {
  const auto s = settings();
  const double a = 3.7e-6;
  gd::IndicatorTracker tracker(s);
  const auto v = tracker.window(on_grid(640, [&](double t) { return 1e-3 + a * std::sin(20 * t); }));
  EXPECT_NEAR(value(v, "kurtosis"), 1.5, 1e-12);
  EXPECT_NEAR(value(v, "rms") / (a / std::sqrt(2.0)), 1.0, 1e-12);
  EXPECT_NEAR(value(v, "crest_factor"), std::sqrt(2.0), 1e-12);
  // FM0: peak-to-peak 2A over the mesh order's amplitude A.
  EXPECT_NEAR(value(v, "fm0"), 2.0, 1e-12);
}

// Gaussian noise: sample kurtosis 3 with standard error sqrt(24 / N) (normal theory); 4 standard
// errors leave a 6e-5 chance to fail on another generator's numbers.
TEST(MonitorIndicators, GaussianKurtosisWithinSamplingError) {
  const int n = 8192;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x(i) = normal(rng);
  EXPECT_NEAR(gd::normalized_moment(x, 4), 3.0, 4.0 * std::sqrt(24.0 / n));
}

// An impulse on one tooth: FM4 is the kurtosis of the impulse with the removed orders (DC, shaft
// orders 1-2, every mesh harmonic and its first sidebands) projected out, computed here by a
// direct O(N^2) DFT; the mesh tone under it is removed entirely. The healthy signal's FM4 (tone
// plus white noise) is a Gaussian's 3.
TEST(MonitorIndicators, Fm4OfOneImpulsiveTooth) {
  const auto s = settings();
  const int n = s.samples_per_revolution, half = n / 2, i0 = 97;
  const double a = 5.0;
  Eigen::VectorXd x = on_grid(n, [](double t) { return 2.0 * std::cos(20 * t) + 0.5 * std::cos(40 * t + 0.3); });
  x(i0) += a;
  auto removed = [&](int k) {
    const int order = k <= half ? k : n - k;
    if (order == 0 || order <= s.shaft_orders) return true;
    const int r = order % s.teeth;
    return r == 0 || r == 1 || r == s.teeth - 1;
  };
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) {
    std::complex<double> sum = 0.0;
    for (int k = 0; k < n; ++k)
      if (!removed(k)) sum += std::polar(a / n, kTwoPi * k * (i - i0) / n);
    d(i) = sum.real();
  }
  const auto signals = gd::decompose(x, s);
  EXPECT_LT((signals.difference - d).cwiseAbs().maxCoeff(), 1e-12 * a);
  gd::IndicatorTracker tracker(s);
  const auto v = tracker.window(x);
  EXPECT_NEAR(value(v, "fm4") / gd::normalized_moment(d, 4), 1.0, 1e-9);
  // Most of an impulse survives the comb: its kurtosis (N^2 - 3N + 3) / (N - 1) = 637 drops by a
  // fraction of that, far above a healthy 3.
  EXPECT_GT(value(v, "fm4"), 100.0);

  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  Eigen::VectorXd healthy = on_grid(n, [](double t) { return 2.0 * std::cos(20 * t); });
  for (int i = 0; i < n; ++i) healthy(i) += 0.1 * normal(rng);
  gd::IndicatorTracker fresh(s);
  // The difference signal keeps ~85 % of N = 640 independent-ish values: 5 standard errors of 3.
  EXPECT_NEAR(value(fresh.window(healthy), "fm4"), 3.0, 5.0 * std::sqrt(24.0 / (0.85 * n)));
}

// NA4 divides by the run's mean residual variance: a second window of twice the residual has
// NA4 = 16 m4 / ((v + 4 v) / 2)^2 = 2.56 kurtosis; the first is the kurtosis itself. NA4* divides
// by the healthy baseline v instead: 16 kurtosis.
TEST(MonitorIndicators, Na4Normalisation) {
  const auto s = settings();
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x = on_grid(640, [](double t) { return std::cos(20 * t); });
  Eigen::VectorXd noise(640);
  for (int i = 0; i < 640; ++i) noise(i) = normal(rng);
  const auto first = gd::decompose(x + noise, s);
  const double v = gd::variance(first.residual), k = gd::normalized_moment(first.residual, 4);
  gd::IndicatorTracker tracker(s, v);
  const auto w1 = tracker.window(x + noise);
  const auto w2 = tracker.window(x + 2.0 * noise);
  EXPECT_NEAR(value(w1, "na4") / k, 1.0, 1e-12);
  EXPECT_NEAR(value(w1, "na4_star") / k, 1.0, 1e-12);
  EXPECT_NEAR(value(w2, "na4") / (2.56 * k), 1.0, 1e-12);
  EXPECT_NEAR(value(w2, "na4_star") / (16.0 * k), 1.0, 1e-12);
  EXPECT_EQ(tracker.windows(), 2);
  // Without a baseline NA4* is not a number, never a made-up one.
  gd::IndicatorTracker no_baseline(s);
  EXPECT_TRUE(std::isnan(value(no_baseline.window(x + noise), "na4_star")));
}

// x = A (1 + m cos theta) cos(Z theta): sidebands A m / 2 at Z +- 1, so SI = A m / 2 and
// SLF = A m / sd(x), sd = A sqrt(1/2 + m^2 / 4).
TEST(MonitorIndicators, SidebandsOfAnAmSignal) {
  const auto s = settings();
  const double a = 2e-3, m = 0.3;
  gd::IndicatorTracker tracker(s);
  const auto v = tracker.window(on_grid(640, [&](double t) { return a * (1 + m * std::cos(t)) * std::cos(20 * t); }));
  EXPECT_NEAR(value(v, "sideband_index") / (a * m / 2), 1.0, 1e-12);
  EXPECT_NEAR(value(v, "sideband_level") / (m / std::sqrt(0.5 + m * m / 4)), 1.0, 1e-12);
}

// The same AM signal's band envelope is 1 + m cos theta: NB4 of one window is its kurtosis about
// the mean, (3 m^4 / 8) / (m^2 / 2)^2 = 1.5; a second window of depth 2m gives
// (3 (2m)^4 / 8) / ((m^2 / 2 + 2 m^2) / 2)^2 = 96 / 25.
TEST(MonitorIndicators, Nb4OnASyntheticEnvelope) {
  const auto s = settings();
  const double m = 0.4;
  const auto am = [&](double depth) {
    return on_grid(640, [&](double t) { return (1 + depth * std::cos(t)) * std::cos(20 * t); });
  };
  const auto signals = gd::decompose(am(m), s);
  const Eigen::VectorXd expected = on_grid(640, [&](double t) { return 1 + m * std::cos(t); });
  EXPECT_LT((signals.envelope - expected).cwiseAbs().maxCoeff(), 1e-12);
  gd::IndicatorTracker tracker(s);
  EXPECT_NEAR(value(tracker.window(am(m)), "nb4"), 1.5, 1e-12);
  EXPECT_NEAR(value(tracker.window(am(2 * m)), "nb4"), 96.0 / 25.0, 1e-12);
}

// A tone at order 7 (neither shaft, mesh nor sideband) is all of the difference signal; the mesh
// tone all of the regular one: energy ratio B / A.
TEST(MonitorIndicators, EnergyRatioAndSignalSplit) {
  const auto s = settings();
  const double a = 2.0, b = 0.25;
  const Eigen::VectorXd x =
      on_grid(640, [&](double t) { return 1.0 + 0.7 * std::cos(t) + a * std::cos(20 * t) + b * std::sin(7 * t); });
  const auto signals = gd::decompose(x, s);
  const Eigen::VectorXd tone = on_grid(640, [&](double t) { return b * std::sin(7 * t); });
  EXPECT_LT((signals.difference - tone).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((signals.residual - tone).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((signals.regular - on_grid(640, [&](double t) { return a * std::cos(20 * t); })).cwiseAbs().maxCoeff(), 1e-12);
  gd::IndicatorTracker tracker(s);
  EXPECT_NEAR(value(tracker.window(x), "energy_ratio"), b / a, 1e-12);
}

TEST(MonitorIndicators, BadSettingsNameTheKeyAndRange) {
  auto s = settings();
  s.samples_per_revolution = 40;
  try {
    gd::validate(s);
    FAIL() << "40 samples per revolution for 20 teeth were accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("monitor.samples_per_revolution = 40"), std::string::npos) << what;
    EXPECT_NE(what.find("allowed [61,"), std::string::npos) << what;
  }
  s = settings();
  s.teeth = 2;
  EXPECT_THROW(gd::validate(s), std::invalid_argument);
  EXPECT_THROW(gd::decompose(Eigen::VectorXd::Zero(100), settings()), std::invalid_argument);
}

// The time-synchronous average and the revolution windows (indicators.cpp).
// A periodic signal sampled at uneven angles over 5 revolutions averages to itself at the grid,
// within linear interpolation's error max|x''| dt^2 / 8 (|x''| <= 400 + 2.7 + 84 here).
TEST(MonitorTsa, PeriodicSignalIsItsOwnAverage) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> step(0.2e-3, 1.0e-3);
  std::vector<double> angle, value;
  for (double t = 0.37; t < 0.37 + 6.3 * kTwoPi; t += step(rng)) {
    angle.push_back(t);
    value.push_back(periodic(t));
  }
  int revolutions = 0;
  const Eigen::VectorXd tsa = gd::time_synchronous_average(value, angle, kTwoPi, 512, &revolutions);
  EXPECT_EQ(revolutions, 5);  // whole revolutions from angle 2 pi on
  const double bound = (400.0 + 2.7 + 84.0) * 1.0e-6 / 8.0;
  for (int i = 0; i < 512; ++i) EXPECT_NEAR(tsa(i), periodic(kTwoPi * i / 512), bound) << i;
}

// White noise of sd s on the grid: the average of N revolutions keeps s / sqrt(N). The sd of 512
// points is estimated within a relative standard error 1 / sqrt(2 * 512) = 3.1 %; 4 of them.
TEST(MonitorTsa, NoiseFallsAsOneOverRootN) {
  const int samples = 512;
  const double sd = 0.5;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal;
  for (int n : {1, 4, 16, 64}) {
    std::vector<double> angle, value;
    for (int i = 0; i <= n * samples; ++i) {
      const double a = kTwoPi * i / samples;
      angle.push_back(a);
      value.push_back(periodic(a) + sd * normal(rng));
    }
    int revolutions = 0;
    const Eigen::VectorXd tsa = gd::time_synchronous_average(value, angle, kTwoPi, samples, &revolutions);
    ASSERT_EQ(revolutions, n);
    double ss = 0;
    for (int i = 0; i < samples; ++i) ss += std::pow(tsa(i) - periodic(kTwoPi * i / samples), 2);
    const double measured = std::sqrt(ss / samples);
    EXPECT_NEAR(measured / (sd / std::sqrt(n)), 1.0, 4.0 / std::sqrt(2.0 * samples)) << n << " revolutions";
  }
}

// Windows of 2 revolutions start at the first multiple of a revolution after the first sample,
// follow each other, carry the mean load of their samples, and a gap restarts them.
TEST(MonitorTsa, WindowsAlignLoadAndRestart) {
  gd::RevolutionWindows windows(kTwoPi, 2, 64);
  std::vector<gd::RevolutionWindow> got;
  const double da = kTwoPi / 200;
  double a = 1.0;
  for (int i = 0; i < 1400; ++i, a += da)
    if (auto w = windows.add(a, periodic(a), 10.0 + (a > 2 * kTwoPi ? 5.0 : 0.0))) got.push_back(*w);
  ASSERT_EQ(got.size(), 3u);  // from 2 pi to (1 + 1399 / 200) 2 pi: 3 windows of 2
  EXPECT_DOUBLE_EQ(got[0].start_angle, kTwoPi);
  EXPECT_DOUBLE_EQ(got[1].start_angle, 3 * kTwoPi);
  EXPECT_NEAR(got[0].mean_load, 10.0 + 5.0 * 0.5, 0.05);  // half its samples beyond 2 revolutions
  EXPECT_NEAR(got[1].mean_load, 15.0, 1e-12);  // all beyond 2 revolutions
  EXPECT_EQ(got[2].index, 2);
  // Linear interpolation on 200 samples per revolution: error below |x''| da^2 / 8.
  for (int i = 0; i < 64; ++i) EXPECT_NEAR(got[1].tsa(i), periodic(kTwoPi * i / 64), 487.0 * da * da / 8) << i;
  // A jump of more than a revolution (an input that stopped) restarts at the next aligned start.
  EXPECT_FALSE(windows.add(a + 3 * kTwoPi, 0.0));
  EXPECT_EQ(windows.restarts(), 1);
  EXPECT_THROW(gd::RevolutionWindows(0.0, 1, 64), std::invalid_argument);
}
