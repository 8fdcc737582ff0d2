#include "gear_dynamics/analysis/over_time.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "gear_dynamics/analysis/report_text.hpp"
#include "gear_dynamics/config/sweep.hpp"
#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_dynamics {

namespace {

using report_text::general;

constexpr double kTimeMatch = 1e-9;  // [s] series times are n h, as the snapshot times
constexpr std::size_t kKdePoints = 201;

// The runs of one kind (stochastic realizations by r, phase runs by j) in group i of the analysis:
// by mu in the mu sweep, by point in a study.
std::vector<const RunRecord*> group_runs(const BatchInputs& in, const BatchAnalysis& a, std::size_t i, RunKind kind) {
  std::vector<const RunRecord*> out;
  for (const RunRecord& r : in.runs)
    if (r.kind == kind && (a.keys.empty() ? r.mu == a.mu[i].mu : r.point == i)) out.push_back(&r);
  std::sort(out.begin(), out.end(), [](const RunRecord* x, const RunRecord* y) { return x->index < y->index; });
  return out;
}

// The phase ensemble's Poincare points after the transient; none (and why) if no phase run has any.
std::optional<GroupSection> section_of(const std::vector<const RunRecord*>& phase_runs, double transient,
                                       std::string& why_not) {
  if (phase_runs.empty()) {
    why_not = "no phase runs (monte_carlo.phase_ensemble false, or none of its bags usable)";
    return std::nullopt;
  }
  GroupSection s;
  for (const RunRecord* r : phase_runs) {
    if (r->section_times.empty()) {
      ++s.runs_without;
      continue;
    }
    bool any = false;
    for (std::size_t k = 0; k < r->section_times.size(); ++k) {
      if (r->section_times[k] < transient - kTimeMatch) continue;
      s.phase.push_back(r->index);
      s.time.push_back(r->section_times[k]);
      s.delta.push_back(r->section_delta[k]);
      s.delta_dot.push_back(r->section_delta_dot[k]);
      any = true;
    }
    if (any) ++s.runs;
  }
  if (s.runs_without == phase_runs.size()) {
    why_not = "the phase runs' bags hold no /gear/poincare points (a batch folder written before the section was "
              "recorded, doc/batch-folder.md §5): the Poincaré section is unavailable";
    return std::nullopt;
  }
  if (s.time.empty()) {
    why_not = "no /gear/poincare point at t >= analysis.poincare_transient = " + general(transient, 6) + " s";
    return std::nullopt;
  }
  if (s.runs_without > 0)
    why_not = std::to_string(s.runs_without) + " of " + std::to_string(phase_runs.size()) +
              " phase runs' bags hold no /gear/poincare points: the section is of the others only";
  return s;
}

// The model of group i (a study point may change the speed, hence f_m).
ModelConfig group_config(const BatchInputs& in, const BatchAnalysis& a, std::size_t i) {
  if (a.keys.empty() || in.points.size() <= i) return in.config;
  return apply_point(in.config, in.axes, in.points[i]);
}

// The mean PSD of delta over the group's densest series, if they resolve the mesh harmonics (each
// run's PSD taken by SeriesDigests::add as it was read).
std::optional<GroupSpectrum> spectrum_of(const std::vector<const SeriesDigests::Run*>& runs, const ModelConfig& c,
                                         double transient, std::string& why_not) {
  GroupSpectrum s;
  s.mesh_frequency = 1.0 / mesh_period(derive(c.gear));
  s.transient = transient;
  double fs = 0;
  for (const SeriesDigests::Run* r : runs) fs = std::max(fs, r->sample_rate);
  if (fs < kDenseRateOverMeshFrequency * s.mesh_frequency) {
    why_not = "no realization has a series at >= " + general(kDenseRateOverMeshFrequency, 3) + " f_m = " +
              general(kDenseRateOverMeshFrequency * s.mesh_frequency, 4) + " Hz (monte_carlo.record_rate, record_realizations)";
    return std::nullopt;
  }
  const double left = c.run.duration - transient;
  const int periods = std::min(kSpectrumSegmentPeriods, static_cast<int>(std::floor(left * s.mesh_frequency + 1e-9)));
  if (periods < 1) {
    why_not = "analysis.spectrum_transient = " + general(transient, 6) + " s leaves less than one mesh period of T = " +
              general(c.run.duration, 6) + " s";
    return std::nullopt;
  }
  std::vector<Psd> psds;
  for (const SeriesDigests::Run* r : runs)
    if (std::abs(r->sample_rate - fs) <= 1e-6 * fs && r->psd) psds.push_back(*r->psd);
  s.first = psds.front();
  s.band = psd_band(psds);
  s.peaks = mark_peaks(s.band.frequency, s.band.mean, s.mesh_frequency, kSpectrumHarmonics);
  return s;
}

// Segments of the ensemble PSD for a series at `rate` (as many mesh periods as fit after the
// transient, at most kSpectrumSegmentPeriods); 0 when not even one does.
std::size_t spectrum_segment(double rate, double mesh_frequency, double duration, double transient) {
  const int periods =
      std::min(kSpectrumSegmentPeriods, static_cast<int>(std::floor((duration - transient) * mesh_frequency + 1e-9)));
  return periods < 1 ? 0 : static_cast<std::size_t>(std::llround(periods * rate / mesh_frequency));
}

Kde kde_of(const std::vector<const RunRecord*>& runs, double RunRecord::*value, const BinSpec& range) {
  std::vector<double> x;
  for (const RunRecord* r : runs) x.push_back(r->*value);
  Kde k;
  k.bandwidth = silverman_bandwidth(x);
  for (std::size_t i = 0; i < kKdePoints; ++i)
    k.grid.push_back(range.lo + (range.hi - range.lo) * static_cast<double>(i) / (kKdePoints - 1));
  k.density = gaussian_kde(x, k.grid, k.bandwidth);
  return k;
}

}  // namespace

void SeriesDigests::add(const BatchInputs& in, const RunRecord& r, const std::vector<double>& t,
                        const std::vector<double>& delta, const std::vector<double>& delta_dot) {
  const std::size_t n = t.size();
  if (n == 0 || delta.size() != n || delta_dot.size() != n)
    throw std::invalid_argument("SeriesDigests::add: an empty series, or times, delta and delta_dot of different lengths");
  const Interval& di = settings_.delta_interval;
  const Interval& vi = settings_.delta_dot_interval;
  Run run;
  run.mu = r.mu;
  run.point = r.point;
  run.realization = r.index;
  run.sample_rate = n < 2 ? 0.0 : static_cast<double>(n - 1) / (t.back() - t.front());
  bool outside = false;  // the previous sample was outside the safe set
  for (std::size_t j = 0; j < n; ++j) {
    const bool inside = di.contains(delta[j]) && vi.contains(delta_dot[j]);
    if (!inside && outside) run.outside.back() = t[j];
    if (!inside && !outside) run.outside.insert(run.outside.end(), {t[j], t[j]});
    outside = !inside;
  }

  // The safety counters at the times all the group's runs recorded so far: the first run's times,
  // then those every later run has as well.
  Group& g = groups_[{r.mu, r.point}];
  const auto count = [&](Time& k, std::size_t j) {
    const bool a = di.contains(delta[j]), b = vi.contains(delta_dot[j]);
    k.joint += a && b;
    k.delta += a;
    k.velocity += b;
    if (std::make_pair(n, r.index) < std::make_pair(k.samples_of, k.realization_of)) {
      k.t = t[j];
      k.samples_of = n;
      k.realization_of = r.index;
    }
  };
  if (g.runs == 0) {
    g.times.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      g.times[j].samples_of = ~std::size_t{0};
      count(g.times[j], j);
    }
  } else {
    std::vector<Time> kept;
    std::size_t j = 0;
    for (Time& k : g.times) {
      while (j < n && t[j] < k.t - kTimeMatch) ++j;
      if (j == n || std::abs(t[j] - k.t) > kTimeMatch) continue;
      count(k, j);
      kept.push_back(k);
    }
    g.times = std::move(kept);
  }
  ++g.runs;

  // This run's PSD, if its series is dense enough for the group's spectrum and at the highest rate
  // so far (spectrum_of uses the runs at the group's highest rate only).
  const auto below = [](double rate, double top) { return std::abs(rate - top) > 1e-6 * top && rate < top; };
  if (below(g.top_rate, run.sample_rate)) {
    g.top_rate = run.sample_rate;
    for (Run& other : runs_)
      if (other.mu == r.mu && other.point == r.point && below(other.sample_rate, g.top_rate)) other.psd.reset();
  }
  auto model = mesh_frequency_duration_.find(r.point);
  if (model == mesh_frequency_duration_.end()) {
    ModelConfig c = in.config;
    if (r.point < in.points.size()) c = apply_point(in.config, in.axes, in.points[r.point]);
    model = mesh_frequency_duration_.emplace(r.point, std::make_pair(1.0 / mesh_period(derive(c.gear)), c.run.duration)).first;
  }
  const auto [mesh_frequency, duration] = model->second;
  const std::size_t segment = spectrum_segment(run.sample_rate, mesh_frequency, duration, settings_.spectrum_transient);
  if (run.sample_rate >= kDenseRateOverMeshFrequency * mesh_frequency && segment > 0 && !below(run.sample_rate, g.top_rate)) {
    std::vector<double> x;
    for (std::size_t j = 0; j < n; ++j)
      if (t[j] >= settings_.spectrum_transient - kTimeMatch) x.push_back(delta[j]);
    run.psd = welch_psd(x, run.sample_rate, WelchOptions{segment, 0.5});
  }
  runs_.push_back(std::move(run));
}

BatchOverTime analyse_over_time(const BatchInputs& in, const BatchAnalysis& a, const SeriesDigests& digests) {
  const AnalysisSettings& s = a.settings;
  BatchOverTime out;
  for (std::size_t i = 0; i < a.mu.size(); ++i) {
    const std::string label = a.keys.empty() ? "mu = " + general(a.mu[i].mu, 6) : "point " + a.keys[i];
    const std::vector<const RunRecord*> all = group_runs(in, a, i, RunKind::Stochastic);
    std::vector<const SeriesDigests::Run*> runs;  // the realizations with a series, by index
    for (const SeriesDigests::Run& r : digests.runs())
      if (a.keys.empty() ? r.mu == a.mu[i].mu : r.point == i) runs.push_back(&r);
    std::sort(runs.begin(), runs.end(), [](const SeriesDigests::Run* x, const SeriesDigests::Run* y) {
      return x->realization < y->realization;
    });
    GroupOverTime grp;
    grp.runs = runs.size();
    for (const SeriesDigests::Run* r : runs) grp.realizations.push_back(r->realization);
    static const std::vector<SeriesDigests::Time> kNoTimes;
    const std::vector<SeriesDigests::Time>& times =
        runs.empty() ? kNoTimes : digests.groups().at({runs.front()->mu, runs.front()->point}).times;
    if (times.empty()) {
      if (!all.empty()) out.notes.push_back(label + ": no recorded series common to the realizations (sparse_record_rate 0?): no safety over time, first passage or spectrum");
    } else {
      const std::size_t n = runs.size();
      for (const SeriesDigests::Time& k : times) {
        grp.safety.time.push_back(k.t);
        grp.safety.joint.push_back(wilson(k.joint, n, s.confidence));
        grp.safety.delta_only.push_back(wilson(k.delta, n, s.confidence));
        grp.safety.velocity_only.push_back(wilson(k.velocity, n, s.confidence));
      }
      if (times.back().t >= s.first_passage_settle - kTimeMatch) {
        // Each run's first common time from the settling time on that lies in one of its
        // stretches outside the safe set; censored at the last common time.
        const double settle = s.first_passage_settle - kTimeMatch;
        FirstPassage passage;
        for (const SeriesDigests::Run* r : runs) {
          bool hit = false;
          double t = times.back().t;
          std::size_t stretch = 0;
          for (const SeriesDigests::Time& k : times) {
            if (k.t < settle) continue;
            while (stretch + 1 < r->outside.size() && r->outside[stretch + 1] < k.t - kTimeMatch) stretch += 2;
            if (stretch + 1 < r->outside.size() && r->outside[stretch] <= k.t + kTimeMatch) {
              hit = true;
              t = k.t;
              break;
            }
          }
          passage.time.push_back(t);
          passage.event.push_back(hit);
        }
        grp.passage = std::move(passage);
        grp.survival = kaplan_meier(grp.passage->time, grp.passage->event, s.confidence);
      } else {
        out.notes.push_back(label + ": analysis.first_passage_settle = " + general(s.first_passage_settle, 6) +
                            " s is after the last recorded time " + general(times.back().t, 6) + " s: no first passage");
      }
      std::string why_not;
      grp.spectrum = spectrum_of(runs, group_config(in, a, i), s.spectrum_transient, why_not);
      if (!grp.spectrum) out.notes.push_back(label + ": no spectrum: " + why_not);
    }
    if (s.kde && all.size() >= 2) {
      grp.kde_delta = kde_of(all, &RunRecord::final_delta, s.delta_bins);
      grp.kde_delta_dot = kde_of(all, &RunRecord::final_delta_dot, s.delta_dot_bins);
    }
    std::string why_no_section;
    grp.section = section_of(group_runs(in, a, i, RunKind::Phase), s.poincare_transient, why_no_section);
    if (!why_no_section.empty()) out.notes.push_back(label + ": Poincaré section: " + why_no_section);
    out.groups.push_back(std::move(grp));
  }
  return out;
}

}  // namespace gear_dynamics
