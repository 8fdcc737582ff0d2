#include "gear_dynamics/maths/spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#include <boost/math/distributions/normal.hpp>

#include "gear_dynamics/maths/statistics.hpp"

namespace gear_dynamics {

Psd welch_psd(const std::vector<double>& x, double sample_rate, const WelchOptions& o) {
  const std::size_t L = o.segment;
  if (L < 8) throw std::invalid_argument("welch_psd: segment must hold at least 8 samples");
  if (!(o.overlap >= 0.0 && o.overlap < 1.0)) throw std::invalid_argument("welch_psd: overlap must be in [0, 1)");
  if (!(sample_rate > 0.0)) throw std::invalid_argument("welch_psd: sample rate must be > 0");
  if (x.size() < L) throw std::invalid_argument("welch_psd: the series is shorter than one segment");
  const std::size_t hop = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(L * (1.0 - o.overlap))));
  // Periodic Hann window (scipy.signal.get_window('hann', L)).
  std::vector<double> w(L);
  double u = 0;
  for (std::size_t i = 0; i < L; ++i) {
    w[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(i) / static_cast<double>(L));
    u += w[i] * w[i];
  }
  const std::size_t nf = L / 2 + 1;
  Psd p;
  p.sample_rate = sample_rate;
  p.segment = L;
  p.overlap = o.overlap;
  p.resolution = sample_rate / static_cast<double>(L);
  double sw = 0;
  for (double v : w) sw += v;
  p.enbw = sample_rate * u / (sw * sw);
  p.frequency.resize(nf);
  p.density.assign(nf, 0.0);
  for (std::size_t k = 0; k < nf; ++k) p.frequency[k] = static_cast<double>(k) * p.resolution;

  Eigen::FFT<double> fft;
  std::vector<double> seg(L);
  std::vector<std::complex<double>> spec;
  for (std::size_t start = 0; start + L <= x.size(); start += hop) {
    double mean = 0;
    for (std::size_t i = 0; i < L; ++i) mean += x[start + i];
    mean /= static_cast<double>(L);
    for (std::size_t i = 0; i < L; ++i) seg[i] = (x[start + i] - mean) * w[i];
    fft.fwd(spec, seg);
    for (std::size_t k = 0; k < nf; ++k) p.density[k] += std::norm(spec[k]);
    ++p.segments;
  }
  const double scale = 1.0 / (sample_rate * u * static_cast<double>(p.segments));
  for (std::size_t k = 0; k < nf; ++k) {
    const bool edge = k == 0 || (L % 2 == 0 && k == nf - 1);  // DC and Nyquist are not doubled
    p.density[k] *= (edge ? 1.0 : 2.0) * scale;
  }
  return p;
}

PsdBand psd_band(const std::vector<Psd>& runs, double confidence) {
  if (runs.empty()) throw std::invalid_argument("psd_band: no runs");
  PsdBand b;
  b.runs = runs.size();
  b.frequency = runs.front().frequency;
  const std::size_t nf = b.frequency.size();
  for (const Psd& r : runs)
    if (r.frequency.size() != nf) throw std::invalid_argument("psd_band: runs differ in their frequency grid");
  const double z = boost::math::quantile(boost::math::normal(), 0.5 + 0.5 * confidence);
  const double n = static_cast<double>(runs.size());
  std::vector<double> col(runs.size());
  for (std::size_t k = 0; k < nf; ++k) {
    double s = 0, ss = 0;
    for (std::size_t r = 0; r < runs.size(); ++r) {
      col[r] = runs[r].density[k];
      s += col[r];
    }
    const double m = s / n;
    for (double v : col) ss += (v - m) * (v - m);
    const double se = runs.size() > 1 ? std::sqrt(ss / (n - 1) / n) : 0.0;
    std::sort(col.begin(), col.end());
    b.mean.push_back(m);
    b.mean_low.push_back(std::max(0.0, m - z * se));
    b.mean_high.push_back(m + z * se);
    b.run_low.push_back(quantile_sorted(col, 0.5 - 0.5 * confidence));
    b.run_high.push_back(quantile_sorted(col, 0.5 + 0.5 * confidence));
  }
  return b;
}

std::vector<SpectralPeak> mark_peaks(const std::vector<double>& f, const std::vector<double>& p, double fm,
                                     int harmonics, int sidebands) {
  std::vector<SpectralPeak> out;
  if (f.size() < 5 || !(fm > 0)) return out;
  const double df = f[1] - f[0];
  const auto label = [&](std::size_t i, bool harm) {
    SpectralPeak s;
    s.frequency = f[i];
    s.density = p[i];
    s.harmonic = static_cast<int>(std::lround(f[i] / fm));
    s.offset = f[i] - s.harmonic * fm;
    s.is_harmonic = harm;
    return s;
  };
  std::vector<bool> taken(f.size(), false);
  const long nbin = static_cast<long>(f.size());
  for (int k = 1; k <= harmonics; ++k) {
    const double fk = k * fm;
    if (fk > f.back()) break;
    const long c = std::lround(fk / df);
    SpectralPeak s = label(static_cast<std::size_t>(c), true);
    s.harmonic = k;
    s.offset = f[c] - fk;
    // Prominence: the bin against the median of the bins 3..10 away on both sides.
    std::vector<double> around;
    for (long i = c - 10; i <= c + 10; ++i)
      if (i >= 1 && i < nbin && std::abs(i - c) >= 3) around.push_back(p[i]);
    std::sort(around.begin(), around.end());
    s.prominence = around.empty() ? 0.0 : p[c] / quantile_sorted(around, 0.5);
    for (long i = std::max(0L, c - 2); i <= std::min(nbin - 1, c + 2); ++i) taken[i] = true;
    out.push_back(s);
  }
  std::vector<std::size_t> maxima;
  for (std::size_t i = 2; i + 2 < f.size(); ++i) {
    if (taken[i] || f[i] < 0.5 * fm) continue;
    if (p[i] > p[i - 1] && p[i] > p[i - 2] && p[i] >= p[i + 1] && p[i] >= p[i + 2]) maxima.push_back(i);
  }
  std::sort(maxima.begin(), maxima.end(), [&](std::size_t a, std::size_t b) { return p[a] > p[b]; });
  for (int j = 0; j < sidebands && j < static_cast<int>(maxima.size()); ++j) out.push_back(label(maxima[j], false));
  return out;
}

}  // namespace gear_dynamics
