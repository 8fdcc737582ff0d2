// Welch PSD against analytic cases (doc/nonlinear-dynamics.md §2): a sine of known amplitude in white
// noise (peak frequency, peak power, noise floor), Parseval, the band of an ensemble, peak marking.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "gear_dynamics/maths/spectrum.hpp"

namespace gd = gear_dynamics;

namespace {

std::vector<double> sine_in_noise(std::size_t n, double fs, double amp, double f0, double noise_sd, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> z(0.0, noise_sd);
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = amp * std::sin(2 * M_PI * f0 * i / fs + 0.3) + z(rng) + 7.0;  // + DC
  return x;
}

}  // namespace

// fs = 1000 Hz, L = 1024 (df = 0.977 Hz), f0 = 128 df = 125 Hz on a bin centre, A = 1, noise sd 0.5,
// 2^18 samples: 511 half-overlapping segments.
TEST(WelchPsd, SineInWhiteNoise) {
  const double fs = 1000, A = 1.0, sd = 0.5, f0 = 125.0;
  const std::size_t L = 1024;
  const auto x = sine_in_noise(1u << 18, fs, A, f0, sd, 42);
  const gd::Psd p = gd::welch_psd(x, fs, {L, 0.5});
  EXPECT_EQ(p.segments, 511u);
  EXPECT_DOUBLE_EQ(p.resolution, fs / L);
  EXPECT_NEAR(p.enbw, 1.5 * fs / L, 1e-9);
  std::size_t k = 1;
  for (std::size_t i = 1; i < p.density.size(); ++i)
    if (p.density[i] > p.density[k]) k = i;
  // Peak frequency to one bin.
  EXPECT_LE(std::abs(p.frequency[k] - f0), p.resolution);
  // Peak density of a bin-centred sine under a Hann window: A^2 / (2 ENBW) = A^2 L / (3 fs) = 0.3413.
  // The sine-noise cross term has relative sd sqrt(2 N/S) ~ 0.055 per segment (N/S = 1.5e-3); over
  // 511 overlapping segments about 0.003: 2 % is more than 6 standard errors.
  const double peak = A * A * L / (3.0 * fs);
  EXPECT_NEAR(p.density[k], peak, 0.02 * peak);
  // Noise floor 2 sd^2 / fs, averaged over the 205 bins of 200-400 Hz: each bin is a chi-square
  // estimate with relative sd about 1/sqrt(511) = 0.044, adjacent Hann bins are correlated (about
  // 100 independent): 0.5 % standard error; 3 % is 6 of them.
  double floor = 0;
  int nb = 0;
  for (std::size_t i = 0; i < p.frequency.size(); ++i)
    if (p.frequency[i] >= 200 && p.frequency[i] <= 400) { floor += p.density[i]; ++nb; }
  floor /= nb;
  EXPECT_NEAR(floor, 2 * sd * sd / fs, 0.03 * 2 * sd * sd / fs);
  // Parseval: sum P df = mean variance of a (mean-removed) segment = A^2/2 + sd^2 = 0.75.
  double total = 0;
  for (double d : p.density) total += d * p.resolution;
  EXPECT_NEAR(total, 0.5 * A * A + sd * sd, 0.02 * 0.75);
}

// Parseval exactly: for one segment, sum P df = sum (w (x - mean))^2 / sum w^2.
TEST(WelchPsd, ParsevalOneSegmentExact) {
  const std::size_t L = 256;
  const auto x = sine_in_noise(L, 100.0, 0.0, 1.0, 1.0, 7);
  const gd::Psd p = gd::welch_psd(x, 100.0, {L, 0.5});
  double mean = 0;
  for (double v : x) mean += v;
  mean /= L;
  double num = 0, u = 0;
  for (std::size_t i = 0; i < L; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2 * M_PI * i / L);
    num += w * w * (x[i] - mean) * (x[i] - mean);
    u += w * w;
  }
  double total = 0;
  for (double d : p.density) total += d * p.resolution;
  // Parseval of the DFT, sum_k |X_k|^2 = L sum y^2, and |X_k| = |X_{L-k}| (doubling is exact).
  EXPECT_NEAR(total, num / u, 1e-12 * num / u);
}

TEST(WelchPsd, RejectsBadOptions) {
  const std::vector<double> x(100, 1.0);
  EXPECT_THROW(gd::welch_psd(x, 1.0, {256, 0.5}), std::invalid_argument);
  EXPECT_THROW(gd::welch_psd(x, 1.0, {64, 1.0}), std::invalid_argument);
  EXPECT_THROW(gd::welch_psd(x, 0.0, {64, 0.5}), std::invalid_argument);
}

TEST(WelchPsd, BandOfIdenticalRunsIsDegenerate) {
  const auto x = sine_in_noise(4096, 100.0, 1.0, 10.0, 0.1, 3);
  const gd::Psd p = gd::welch_psd(x, 100.0, {512, 0.5});
  const gd::PsdBand b = gd::psd_band({p, p, p});
  ASSERT_EQ(b.mean.size(), p.density.size());
  for (std::size_t i = 0; i < p.density.size(); ++i) {
    EXPECT_NEAR(b.mean[i], p.density[i], 1e-12 * (p.density[i] + 1e-300));
    EXPECT_NEAR(b.mean_high[i], b.mean[i], 1e-12 * (b.mean[i] + 1e-300));
    EXPECT_DOUBLE_EQ(b.run_low[i], p.density[i]);
  }
}

TEST(MarkPeaks, FindsHarmonicsAndSidebands) {
  // Mesh frequency 100 Hz, harmonics at 100, 200, 300 and a sideband at 230 Hz.
  const double fs = 2000;
  std::vector<double> x(1 << 16);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> z(0, 0.01);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double t = i / fs;
    x[i] = std::sin(2 * M_PI * 100 * t) + 0.5 * std::sin(2 * M_PI * 200 * t) + 0.25 * std::sin(2 * M_PI * 300 * t) +
           0.1 * std::sin(2 * M_PI * 230 * t) + z(rng);
  }
  const gd::Psd p = gd::welch_psd(x, fs, {2048, 0.5});
  const auto peaks = gd::mark_peaks(p.frequency, p.density, 100.0, 3, 1);
  ASSERT_EQ(peaks.size(), 4u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(peaks[k].is_harmonic);
    EXPECT_EQ(peaks[k].harmonic, k + 1);
    EXPECT_LE(std::abs(peaks[k].frequency - 100.0 * (k + 1)), p.resolution);
  }
  EXPECT_FALSE(peaks[3].is_harmonic);
  EXPECT_EQ(peaks[3].harmonic, 2);
  EXPECT_NEAR(peaks[3].offset, 30.0, p.resolution);
}

