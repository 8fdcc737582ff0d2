#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/analysis/report_text.hpp"
#include "gear_dynamics/report/report_file.hpp"
#include "sections.hpp"

namespace gear_dynamics {

namespace fs = std::filesystem;

namespace {

using report_text::fixed;
using report_text::general;
using report_text::percent;

constexpr double U = kToPaperUnits;

struct Spread {
  double mean = 0, sd = 0, min = 0, max = 0;
};
Spread spread_of(const std::vector<double>& x) {
  Spread s;
  if (x.empty()) return s;
  s.min = *std::min_element(x.begin(), x.end());
  s.max = *std::max_element(x.begin(), x.end());
  double sum = 0;
  for (double v : x) sum += v;
  s.mean = sum / static_cast<double>(x.size());
  double ss = 0;
  for (double v : x) ss += (v - s.mean) * (v - s.mean);
  s.sd = x.size() > 1 ? std::sqrt(ss / static_cast<double>(x.size() - 1)) : 0.0;
  return s;
}

// What the files and the section over time are written from, and the list of files written.
struct OverTimeFiles {
  fs::path dir;
  const BatchInputs& in;
  const BatchAnalysis& a;
  const BatchOverTime& o;
  const AnalysisSettings& s;
  std::string kh;      // row keys: mu for the mu sweep (format 1), else the point and its values
  std::string head;    // the key column's heading in report.md
  std::string pct;     // the confidence, "95 %"
  std::string di, vi;  // the safe set's intervals (delta, delta_dot) as report.md prints them
  std::vector<std::string>& written;

  std::string key(std::size_t i) const { return a.keys.empty() ? general(a.mu[i].mu) : a.keys[i]; }
  std::string label(std::size_t i) const { return a.keys.empty() ? fixed(a.mu[i].mu, 2) : a.keys[i]; }

  void write_safety_csv() const;
  void write_first_passage_csv() const;
  void write_spectrum_csv() const;
  void write_poincare_csv() const;
  void write_kde_csv() const;
  void md_safety(std::ostream& r) const;
  void md_first_passage(std::ostream& r) const;
  void md_spectrum(std::ostream& r) const;
  void md_kde(std::ostream& r) const;
  void md_poincare(std::ostream& r) const;
  void md_notes(std::ostream& r) const;
};

// safety_over_time.csv: P(both intervals) and each alone at every common recorded time.
void OverTimeFiles::write_safety_csv() const {
  ReportFile c(dir / "safety_over_time.csv", written,
               kh + ",t[s],quantity,successes,trials,estimate,wilson_low,wilson_high");
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    const SafetySeries& ss = o.groups[i].safety;
    for (std::size_t j = 0; j < ss.time.size(); ++j)
      for (const auto& [name, p] : {std::pair<const char*, const Proportion&>{"joint", ss.joint[j]},
                                    {"delta", ss.delta_only[j]}, {"delta_dot", ss.velocity_only[j]}})
        c.line(key(i)) << ',' << general(ss.time[j]) << ',' << name << ',' << p.successes << ',' << p.trials << ','
                       << general(p.estimate) << ',' << general(p.low) << ',' << general(p.high) << '\n';
  }
}

// first_passage.csv, survival.csv: each realization's first passage and the Kaplan-Meier curve.
void OverTimeFiles::write_first_passage_csv() const {
  ReportFile fp(dir / "first_passage.csv", written, kh + ",realization,t[s],event");
  ReportFile km(dir / "survival.csv", written, kh + ",t[s],at_risk,events,survival,low,high");
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    const GroupOverTime& grp = o.groups[i];
    if (!grp.passage) continue;
    for (std::size_t r = 0; r < grp.realizations.size(); ++r)
      fp.line(key(i)) << ',' << grp.realizations[r] << ',' << general(grp.passage->time[r]) << ','
                      << (grp.passage->event[r] ? 1 : 0) << '\n';
    // First row: the settling time, where every realization is at risk and S = 1.
    km.line(key(i)) << ',' << general(s.first_passage_settle) << ',' << grp.passage->time.size() << ",0,1,1,1\n";
    const KaplanMeier& k = grp.survival;
    for (std::size_t j = 0; j < k.time.size(); ++j)
      km.line(key(i)) << ',' << general(k.time[j]) << ',' << k.at_risk[j] << ',' << k.events[j] << ',' << general(k.survival[j])
                      << ',' << general(k.low[j]) << ',' << general(k.high[j]) << '\n';
  }
}

// spectrum_band.csv, spectrum_peaks.csv, spectrum_info.csv: the mean Welch PSD of delta, its lines, its settings.
void OverTimeFiles::write_spectrum_csv() const {
  const double U2 = U * U;
  ReportFile band(dir / "spectrum_band.csv", written,
                  kh + ",f[Hz],mean[mm^2/Hz],mean_low[mm^2/Hz],mean_high[mm^2/Hz],run_low[mm^2/Hz],run_high[mm^2/Hz]");
  ReportFile peaks(dir / "spectrum_peaks.csv", written,
                   kh + ",f[Hz],density[mm^2/Hz],harmonic,offset[Hz],is_harmonic,prominence");
  ReportFile info(dir / "spectrum_info.csv", written,
                  kh + ",mesh_frequency[Hz],sample_rate[Hz],resolution[Hz],enbw[Hz],segment,overlap,segments,runs,"
                       "transient[s]");
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    if (!o.groups[i].spectrum) continue;
    const GroupSpectrum& sp = *o.groups[i].spectrum;
    const PsdBand& b = sp.band;
    for (std::size_t k = 0; k < b.frequency.size(); ++k)
      band.line(key(i)) << ',' << general(b.frequency[k]) << ',' << general(b.mean[k] * U2) << ',' << general(b.mean_low[k] * U2) << ','
                        << general(b.mean_high[k] * U2) << ',' << general(b.run_low[k] * U2) << ',' << general(b.run_high[k] * U2) << '\n';
    for (const SpectralPeak& p : sp.peaks)
      peaks.line(key(i)) << ',' << general(p.frequency) << ',' << general(p.density * U2) << ',' << p.harmonic << ','
                         << general(p.offset) << ',' << (p.is_harmonic ? 1 : 0) << ',' << general(p.prominence) << '\n';
    info.line(key(i)) << ',' << general(sp.mesh_frequency) << ',' << general(sp.first.sample_rate) << ',' << general(sp.first.resolution)
                      << ',' << general(sp.first.enbw) << ',' << sp.first.segment << ',' << general(sp.first.overlap) << ','
                      << sp.first.segments << ',' << b.runs << ',' << general(sp.transient) << '\n';
  }
}

// poincare.csv: the phase ensemble's Poincare points.
void OverTimeFiles::write_poincare_csv() const {
  ReportFile c(dir / "poincare.csv", written, kh + ",phase,t[s],delta[mm],delta_dot[mm/s]");
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    if (!o.groups[i].section) continue;
    const GroupSection& sec = *o.groups[i].section;
    for (std::size_t k = 0; k < sec.time.size(); ++k)
      c.line(key(i)) << ',' << sec.phase[k] << ',' << general(sec.time[k]) << ',' << general(sec.delta[k] * U) << ','
                     << general(sec.delta_dot[k] * U) << '\n';
  }
}

// kde.csv: the kernel density estimates of delta(T) and delta_dot(T), if analysis.kde.
void OverTimeFiles::write_kde_csv() const {
  if (!s.kde) return;
  ReportFile c(dir / "kde.csv", written, kh + ",quantity,unit,bandwidth,x,density");
  for (std::size_t i = 0; i < o.groups.size(); ++i)
    for (const auto& [name, unit, kde] : {std::tuple<const char*, const char*, const std::optional<Kde>&>{
                                              "delta_T", "mm", o.groups[i].kde_delta},
                                          {"delta_dot_T", "mm/s", o.groups[i].kde_delta_dot}})
      if (kde)
        for (std::size_t k = 0; k < kde->grid.size(); ++k)
          c.line(key(i)) << ',' << name << ',' << unit << ',' << general(kde->bandwidth * U) << ',' << general(kde->grid[k] * U)
                         << ',' << general(kde->density[k] / U) << '\n';
}

// report.md: Safety over time: P(both) at the snapshot times.
void OverTimeFiles::md_safety(std::ostream& r) const {
  // Columns of the safety table: the snapshot times on the common grid, so t = T is among them.
  std::vector<double> times;
  for (double t : in.config.run.snapshot_times)
    for (const GroupOverTime& grp : o.groups)
      if (std::any_of(grp.safety.time.begin(), grp.safety.time.end(), [&](double x) { return std::abs(x - t) <= 1e-6; })) {
        times.push_back(t);
        break;
      }
  r << "\n## Safety over time (doc/nonlinear-dynamics.md §6)\n\n"
       "The stochastic realizations' recorded series (every state at `monte_carlo.sparse_record_rate`; the dense "
       "realizations on the same times) give P(δ ∈ " << di << " ∧ δ̇ ∈ " << vi << ") and each interval alone at "
       "every recorded time, with " << pct << " Wilson intervals (safety_over_time.csv, all times). At t = T the "
       "two marginals are Table 4's probabilities (the same states).\n\n| " << head << " | n |";
  for (double t : times) r << " P(both) at " << general(t, 6) << " s [" << pct << "] (%) |";
  r << "\n|---|---|";
  for (std::size_t k = 0; k < times.size(); ++k) r << "---|";
  r << "\n";
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    const SafetySeries& ss = o.groups[i].safety;
    r << "| " << label(i) << " | " << o.groups[i].runs << " |";
    for (double t : times) {
      std::size_t j = 0;
      while (j < ss.time.size() && std::abs(ss.time[j] - t) > 1e-6) ++j;
      r << " " << (j < ss.time.size() ? percent(ss.joint[j]) : "–") << " |";
    }
    r << "\n";
  }
  r << "\n![Safety over time](safety_over_time.png)\n";
}

// report.md: First passage out of the safe set, Kaplan-Meier survival.
void OverTimeFiles::md_first_passage(std::ostream& r) const {
  r << "\n## First passage out of the safe set\n\n"
       "Per realization, the first recorded time t ≥ " << general(s.first_passage_settle, 6) << " s "
       "(`analysis.first_passage_settle`, after the start-up) at which (δ, δ̇) is outside the safe set above; a "
       "realization that stays inside is censored at the last recorded time. Excursions between two records are not "
       "seen, so this is the first passage of the recorded series (an upper bound of the true one). Kaplan–Meier "
       "survival S(t) = P(no exit in [settle, t]) with Greenwood's variance and the log(−log) " << pct << " interval "
       "(first_passage.csv, survival.csv).\n\n"
       "| " << head << " | n | exits | censored | S(T) [" << pct << "] | median first passage [s] |\n"
       "|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    const GroupOverTime& grp = o.groups[i];
    if (!grp.passage) {
      r << "| " << label(i) << " | " << grp.runs << " | – | – | – | – |\n";
      continue;
    }
    const std::size_t exits = static_cast<std::size_t>(std::count(grp.passage->event.begin(), grp.passage->event.end(), true));
    const KaplanMeier& k = grp.survival;
    std::string median = "> T";
    for (std::size_t j = 0; j < k.time.size(); ++j)
      if (k.survival[j] <= 0.5) {
        median = general(k.time[j], 6);
        break;
      }
    const std::string st = k.time.empty() ? "1" : fixed(k.survival.back(), 3) + " [" + fixed(k.low.back(), 3) + ", " +
                                                      fixed(k.high.back(), 3) + "]";
    r << "| " << label(i) << " | " << grp.passage->time.size() << " | " << exits << " | "
      << grp.passage->time.size() - exits << " | " << st << " | " << median << " |\n";
  }
  r << "\n![First passage and Kaplan–Meier survival](first_passage.png)\n";
}

// report.md: Spectrum of delta: the mean Welch PSD's harmonics.
void OverTimeFiles::md_spectrum(std::ostream& r) const {
  r << "\n## Spectrum of δ (doc/nonlinear-dynamics.md §2)\n\n"
       "Mean one-sided Welch PSD of δ over the realizations with a dense series (S2, S3, … at "
       "`monte_carlo.record_rate`), after t = " << general(s.spectrum_transient, 6) << " s (`analysis.spectrum_transient`): "
       "periodic Hann window, segments of " << kSpectrumSegmentPeriods << " mesh periods (fewer if the series is "
       "shorter) overlapping by 50 %, so every harmonic k·f_m is a bin centre. Band: the " << pct
    << " normal-approximation interval of the mean, and the pointwise range of the single runs (spectrum_band.csv). "
       "Prominence: the density at k·f_m over the median of the bins 3–10 away (≈ 1: no line; spectrum_peaks.csv).\n\n"
       "| " << head << " | runs | f_m [Hz] | Δf [Hz] | segments |";
  const bool any_spectrum =
      std::any_of(o.groups.begin(), o.groups.end(), [](const GroupOverTime& x) { return x.spectrum.has_value(); });
  for (int k = 1; k <= kSpectrumHarmonics; ++k) r << " prominence " << k << " f_m |";
  r << "\n|---|---|---|---|---|";
  for (int k = 1; k <= kSpectrumHarmonics; ++k) r << "---|";
  r << "\n";
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    if (!o.groups[i].spectrum) continue;
    const GroupSpectrum& sp = *o.groups[i].spectrum;
    r << "| " << label(i) << " | " << sp.band.runs << " | " << fixed(sp.mesh_frequency, 1) << " | "
      << fixed(sp.first.resolution, 2) << " | " << sp.first.segments << " |";
    for (int k = 1; k <= kSpectrumHarmonics; ++k) {
      const auto p = std::find_if(sp.peaks.begin(), sp.peaks.end(),
                                  [&](const SpectralPeak& x) { return x.is_harmonic && x.harmonic == k; });
      r << " " << (p == sp.peaks.end() ? "–" : fixed(p->prominence, 2)) << " |";
    }
    r << "\n";
  }
  r << (any_spectrum ? "\n![Spectrum band of δ](spectrum_band.png)\n" : "\n(none computed: see below)\n");
}

// report.md: Kernel density estimates beside Figs. 11 and 12, if analysis.kde.
void OverTimeFiles::md_kde(std::ostream& r) const {
  if (s.kde) {
    r << "\n## Kernel density estimates beside Figs. 11 and 12 (doc/nonlinear-dynamics.md §7)\n\n"
         "Gaussian kernel, bandwidth by Silverman's rule of thumb h = 0.9·min(sd, IQR/1.34)·n^(−1/5) (kde.csv), "
         "drawn over the histograms. A kernel smears the hard edge of δ at contact over about one bandwidth.\n\n"
         "| " << head << " | n | h for δ(T) [mm] | h for δ̇(T) [mm/s] |\n|---|---|---|---|\n";
    for (std::size_t i = 0; i < o.groups.size(); ++i)
      if (o.groups[i].kde_delta)
        r << "| " << label(i) << " | " << a.mu[i].stochastic_runs << " | " << general(o.groups[i].kde_delta->bandwidth * U, 3)
          << " | " << general(o.groups[i].kde_delta_dot->bandwidth * U, 3) << " |\n";
  }
}

// report.md: Poincare section of the phase ensemble.
void OverTimeFiles::md_poincare(std::ostream& r) const {
  r << "\n## Poincaré section of the phase ensemble (doc/nonlinear-dynamics.md §3)\n\n"
       "(δ, δ̇) of every phase run (φ0 = j·φn/64) at mesh phase 0 once per mesh period T_m, as the batch recorded them "
       "(`/gear/poincare`, doc/batch-folder.md §5: grid states where t_k = (φn − φ0)/Ω + k·T_m is on the integration "
       "grid, otherwise interpolated within the step, cubic Hermite in δ and its slope for δ̇), from t = "
    << general(s.poincare_transient, 6) << " s on (`analysis.poincare_transient`, after the start-up; poincare.csv). "
       "A periodic response would put each run's points on a few fixed points; a cloud is the aperiodic rattle.\n\n"
       "| " << head << " | phase runs | points | δ mean ± sd [mm] | δ min – max [mm] | δ̇ mean ± sd [mm/s] | "
       "δ̇ min – max [mm/s] |\n|---|---|---|---|---|---|---|\n";
  const bool any_section =
      std::any_of(o.groups.begin(), o.groups.end(), [](const GroupOverTime& x) { return x.section.has_value(); });
  for (std::size_t i = 0; i < o.groups.size(); ++i) {
    if (!o.groups[i].section) {
      r << "| " << label(i) << " | – | unavailable (below) | – | – | – | – |\n";
      continue;
    }
    const GroupSection& sec = *o.groups[i].section;
    const Spread d = spread_of(sec.delta), v = spread_of(sec.delta_dot);
    r << "| " << label(i) << " | " << sec.runs << " | " << sec.time.size() << " | " << fixed(d.mean * U, 5) << " ± "
      << fixed(d.sd * U, 5) << " | " << fixed(d.min * U, 5) << " – " << fixed(d.max * U, 5) << " | " << fixed(v.mean * U, 2)
      << " ± " << fixed(v.sd * U, 2) << " | " << fixed(v.min * U, 2) << " – " << fixed(v.max * U, 2) << " |\n";
  }
  r << (any_section ? "\n![Poincaré section of the phase ensemble](poincare.png)\n" : "\n(none: see below)\n");
}

// report.md: What was not computed, and why.
void OverTimeFiles::md_notes(std::ostream& r) const {
  if (!o.notes.empty()) {
    r << "\nNot computed:\n\n";
    for (const std::string& n : o.notes) r << "- " << n << "\n";
  }
}

}  // namespace

std::string write_over_time(const std::string& folder, const BatchInputs& in, const BatchAnalysis& a,
                            const BatchOverTime& o, std::vector<std::string>& written) {
  const fs::path dir(folder);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create report folder " + folder + ": " + ec.message());
  const AnalysisSettings& s = a.settings;
  const std::string kh = a.key_header.empty() ? "mu" : a.key_header;
  std::string head = a.keys.empty() ? "μ" : kh;
  for (std::size_t p = head.find(','); p != std::string::npos; p = head.find(',', p + 2)) head.replace(p, 1, ", ");
  const OverTimeFiles files{
      dir, in, a, o, s, kh, head, std::to_string(static_cast<int>(std::lround(100 * s.confidence))) + " %",
      "[" + fixed(s.delta_interval.lo * U, 4) + ", " + fixed(s.delta_interval.hi * U, 4) + "] mm",
      "[" + fixed(s.delta_dot_interval.lo * U, 1) + ", " + fixed(s.delta_dot_interval.hi * U, 1) + "] mm/s", written};
  files.write_safety_csv();
  files.write_first_passage_csv();
  files.write_spectrum_csv();
  files.write_poincare_csv();
  files.write_kde_csv();
  std::ostringstream r;
  files.md_safety(r);
  files.md_first_passage(r);
  files.md_spectrum(r);
  files.md_kde(r);
  files.md_poincare(r);
  files.md_notes(r);
  return r.str();
}

}  // namespace gear_dynamics
