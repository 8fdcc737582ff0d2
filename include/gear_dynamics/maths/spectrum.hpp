// Power spectral densities by Welch's method (doc/nonlinear-dynamics.md §2): one-sided, Hann window,
// segments overlapping by a stated fraction, the mean removed per segment (scipy's 'constant'
// detrend), density in unit^2/Hz so that sum(P) * df equals the variance (Parseval). An ensemble of
// runs gives the mean PSD with a confidence band; peaks are marked against the mesh frequency.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace gear_dynamics {

struct WelchOptions {
  std::size_t segment = 8192;  // samples per segment (any length; FFT by Eigen/kissfft)
  double overlap = 0.5;        // fraction of a segment shared with the next, in [0, 1)
};

struct Psd {
  std::vector<double> frequency;  // [Hz], 0 .. fs/2, step fs / segment
  std::vector<double> density;    // one-sided [unit^2/Hz]
  double sample_rate = 0, resolution = 0;  // fs [Hz], bin width fs/segment [Hz]
  double enbw = 0;                // equivalent noise bandwidth of the window, 1.5 fs/segment for Hann [Hz]
  std::size_t segment = 0, segments = 0;
  double overlap = 0;
};

// Throws std::invalid_argument when x is shorter than one segment or the options are invalid.
Psd welch_psd(const std::vector<double>& x, double sample_rate, const WelchOptions& options = {});

// Mean PSD of runs with equal frequency grids, a normal-approximation confidence band of the mean
// (mean +- z sd / sqrt(n)) and the pointwise (1 - confidence)/2 and (1 + confidence)/2 quantiles of
// the single runs (type 7).
struct PsdBand {
  std::vector<double> frequency, mean, mean_low, mean_high, run_low, run_high;
  std::size_t runs = 0;
};
PsdBand psd_band(const std::vector<Psd>& runs, double confidence = 0.95);

// Peaks of a PSD: for each mesh harmonic k f_m (k = 1 .. harmonics) the bin nearest to it (exactly
// on it when the segment holds a whole number of mesh periods) with its prominence, and the `sidebands` largest other local maxima (a bin above its two neighbours on
// each side) at or above f_m / 2, each labelled by its offset from the nearest harmonic.
struct SpectralPeak {
  double frequency = 0, density = 0;
  int harmonic = 0;       // nearest harmonic k
  double offset = 0;      // frequency - k f_m [Hz]
  bool is_harmonic = false;
  double prominence = 0;  // harmonics: density / median density of the bins 3..10 away (1: no line)
};
// The sidebands n f_m + k f_r (n = 1 .. harmonics, k = -orders .. orders but 0) that a gear whose
// teeth differ (a fault, profile errors) puts around the mesh harmonics, f_r its rotation frequency.
// A sideband is a line where the largest bin within one bin of it is a local maximum.
struct Sideband {
  int harmonic = 0, order = 0;
  double frequency = 0;      // n f_m + k f_r [Hz]
  double bin_frequency = 0;  // the largest bin within one bin of it [Hz]
  double density = 0;
  bool line = false;
};
std::vector<Sideband> sidebands(const std::vector<double>& frequency, const std::vector<double>& density,
                                double mesh_frequency, double rotation_frequency, int harmonics, int orders);

std::vector<SpectralPeak> mark_peaks(const std::vector<double>& frequency, const std::vector<double>& density,
                                     double mesh_frequency, int harmonics = 5, int sidebands = 8);

}  // namespace gear_dynamics
