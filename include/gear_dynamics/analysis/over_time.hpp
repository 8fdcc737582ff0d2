// The batch-level analyses of the aggregator's report over time (doc/gear_aggregator.md §5,
// doc/nonlinear-dynamics.md §6, §7): per group of the report (mu, or study point) safety over time
// with Wilson bands, first passage out of the safe set with its Kaplan-Meier survival curve, the
// mean Welch PSD of delta over the realizations with a dense series, KDEs of delta(T) and
// delta_dot(T), and the Poincare section of the phase ensemble. The report layer writes them. No ROS.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gear_dynamics/analysis/batch_analysis.hpp"
#include "gear_dynamics/batch/run_record.hpp"
#include "gear_dynamics/maths/safety.hpp"
#include "gear_dynamics/maths/spectrum.hpp"

namespace gear_dynamics {

// Segments of the ensemble PSD: this many mesh periods (fewer if the series is shorter), so every
// mesh harmonic lies on a bin centre (as gear_analyze spectrum).
constexpr int kSpectrumSegmentPeriods = 30;
constexpr int kSpectrumHarmonics = 5;
// A series is dense enough for the spectrum when its sample rate is at least this many times f_m
// (harmonics 1..5 below Nyquist); the sparse 100 Hz series is not.
constexpr double kDenseRateOverMeshFrequency = 2.0 * kSpectrumHarmonics;

struct GroupSpectrum {
  double mesh_frequency = 0, transient = 0;
  Psd first;      // the first run's PSD: rate, resolution, segments (the band has the densities)
  PsdBand band;   // over the runs with the densest series
  std::vector<SpectralPeak> peaks;  // of the mean PSD
};

struct Kde {
  double bandwidth = 0;  // Silverman's rule [SI]
  std::vector<double> grid, density;
};

// The Poincare section of a group's phase ensemble (doc/nonlinear-dynamics.md §3): the
// /gear/poincare points of its phase runs at t >= analysis.poincare_transient, by phase index j
// then time.
struct GroupSection {
  std::size_t runs = 0;                // phase runs with points after the transient
  std::size_t runs_without = 0;        // phase runs whose bag holds no point (an older batch)
  std::vector<std::uint32_t> phase;    // per point: the run's phase index j
  std::vector<double> time, delta, delta_dot;  // [s], [m], [m/s]
};

// One group of the report (an entry of BatchAnalysis::mu), its stochastic realizations.
struct GroupOverTime {
  std::size_t runs = 0;             // realizations with a series
  std::vector<std::uint32_t> realizations;  // their indices, in the order of the series below
  SafetySeries safety;              // at the times every such realization recorded
  std::optional<FirstPassage> passage;  // none when no recorded time is >= the settling time
  KaplanMeier survival;
  std::optional<GroupSpectrum> spectrum;
  std::optional<Kde> kde_delta, kde_delta_dot;
  std::optional<GroupSection> section;  // none without phase runs with /gear/poincare points
};

struct BatchOverTime {
  std::vector<GroupOverTime> groups;  // parallel to BatchAnalysis::mu
  std::vector<std::string> notes;     // what could not be computed, and why
};

// What the analyses over time keep of the stochastic runs' state series, reduced as each run is
// read so that no series is kept (the aggregator's memory does not grow with their length):
// per group, the safety counters at the times every realization of it recorded so far; per run,
// its stretches outside the safe set (first passage), its sample rate and, for a series dense
// enough for the spectrum, its Welch PSD. The result does not depend on the order of add().
class SeriesDigests {
 public:
  explicit SeriesDigests(const AnalysisSettings& settings) : settings_(settings) {}

  // One stochastic run's /gear/state series [s], [m], [m/s] (non-empty, ascending times); `in`
  // gives the model of the run's group (its study point). Throws std::invalid_argument on series
  // of different lengths.
  void add(const BatchInputs& in, const RunRecord& run, const std::vector<double>& time,
           const std::vector<double>& delta, const std::vector<double>& delta_dot);

  // A recorded time with how many of the group's runs were inside the intervals there.
  struct Time {
    double t = 0;  // the value of the shortest series (the first by realization among equals)
    std::size_t samples_of = 0;  // that series' length, and its realization
    std::uint32_t realization_of = 0;
    std::size_t joint = 0, delta = 0, velocity = 0;
  };
  struct Group {
    std::size_t runs = 0;
    double top_rate = 0;  // the highest sample rate of its runs so far: only those have a PSD
    std::vector<Time> times;  // the times all its runs recorded (within 1e-9 s), ascending
  };
  struct Run {
    double mu = 0;
    std::size_t point = 0;
    std::uint32_t realization = 0;
    std::vector<double> outside;  // [start, end] pairs: maximal stretches of samples outside the safe set
    double sample_rate = 0;       // (n - 1) / (t_last - t_first) [Hz]
    std::optional<Psd> psd;       // if the series is dense enough for the spectrum and of the group's top rate
  };
  // Groups keyed by (mu, point): one group of the report either way (mu sweep or study).
  const std::map<std::pair<double, std::size_t>, Group>& groups() const { return groups_; }
  const std::vector<Run>& runs() const { return runs_; }

 private:
  AnalysisSettings settings_;
  std::map<std::pair<double, std::size_t>, Group> groups_;
  std::vector<Run> runs_;
  std::map<std::size_t, std::pair<double, double>> mesh_frequency_duration_;  // per point
};

BatchOverTime analyse_over_time(const BatchInputs& inputs, const BatchAnalysis& analysis, const SeriesDigests& series);

}  // namespace gear_dynamics
