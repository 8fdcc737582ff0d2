// The time-synchronous average and the revolution windows against closed forms (doc/monitor.md §7).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "gear_dynamics/monitor/indicators.hpp"

namespace gd = gear_dynamics;

namespace {
constexpr double kTwoPi = 6.283185307179586;
double periodic(double t) { return std::cos(20 * t) + 0.3 * std::sin(3 * t + 0.2) + 0.05 * std::cos(41 * t); }
}  // namespace

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
