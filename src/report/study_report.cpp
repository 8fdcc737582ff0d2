#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
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

std::string median_ci(const BoxStats& b, double scale, int decimals) {
  if (b.n == 0) return "–";
  return fixed(b.median * scale, decimals) + " [" + fixed(b.median_low * scale, decimals) + ", " +
         fixed(b.median_high * scale, decimals) + "]";
}

// "p = 0.1234", "p < 1e-4" or "p not defined", with "(exact sign test)" where the p is exact.
std::string p_text(const RankTest& t) {
  if (!t.valid) return "p not defined";
  const std::string exact = t.exact ? " (exact sign test)" : "";
  if (t.p_value < 1e-4) return "p < 1e-4" + exact;
  return "p = " + fixed(t.p_value, 4) + exact;
}

// A value of axis `a` as reports write it: a text axis's label, else the number.
std::string axis_value(const StudyAnalysis& s, std::size_t a, double v, int digits = 0) {
  if (s.axes[a].text()) return s.axes[a].value_text(v);
  return digits ? general(v, digits) : general(v);
}

// "load.sigma = 5, gear_pair.friction_coefficient = 0.04" for the fixed axes of a slice.
std::string fixed_text(const StudyAnalysis& s, const AxisSlice& l, const char* sep, const char* eq) {
  std::string t;
  for (std::size_t a = 0; a < s.axes.size(); ++a) {
    if (a == l.axis || s.axes[a].values.size() < 2) continue;
    t += (t.empty() ? "" : sep) + column_name(s.axes[a].key) + eq + axis_value(s, a, l.fixed[a], 6);
  }
  return t;
}

void proportion_fields(std::ostream& o, const Proportion& p) {
  o << ',' << p.successes << ',' << p.trials << ',' << general(p.estimate) << ',' << general(p.low) << ',' << general(p.high);
}

}  // namespace

namespace {

// points.csv: one row per point, every statistic.
void write_points_csv(const fs::path& dir, const StudyAnalysis& st, std::vector<std::string>& written) {
  ReportFile file(dir / "points.csv", written);
  std::ostream& o = file.out();
  o << "point";
  for (const SweepAxis& a : st.axes) o << ',' << column_name(a.key);
  o << ",R,d_min[mm*s^-1/2],d_q1,d_median,d_median_low,d_median_high,d_q3,d_max,phase_n,phase_d_median[mm*s^-1/2],"
       "s1_d[mm*s^-1/2]";
  for (const char* p : {"d>median_phase_d", "d>d_S1", "delta_T_in", "delta_dot_T_in", "both_in", "t_ss<T"})
    o << ',' << p << "_k," << p << "_n," << p << ',' << p << "_low," << p << "_high";
  o << ",t_ss_median[s],t_ss_median_low,t_ss_median_high,t_ss_q1,t_ss_q3,delta_T_median[mm],delta_dot_T_median[mm/s],"
       "phi_T_mean[mm/s^2],phi_T_sd[mm/s^2]\n";
  for (const PointAnalysis& p : st.points) {
    const MuAnalysis& m = p.stats;
    const BoxStats& d = m.center_distance;
    o << p.point;
    for (std::size_t a = 0; a < p.values.size(); ++a) o << ',' << axis_value(st, a, p.values[a]);
    o << ',' << d.n << ',' << general(d.min * U) << ',' << general(d.q1 * U) << ',' << general(d.median * U) << ',' << general(d.median_low * U)
      << ',' << general(d.median_high * U) << ',' << general(d.q3 * U) << ',' << general(d.max * U) << ',' << m.phase_runs << ','
      << general(m.phase_center_distance.median * U) << ',' << general(m.s1 ? m.s1->center_distance * U : std::nan(""));
    for (const Proportion* q : {&m.d_exceeds_phase_median, &m.d_exceeds_s1, &m.delta_in_interval,
                                &m.delta_dot_in_interval, &p.both_in_interval, &m.reached_steady_state})
      proportion_fields(o, *q);
    const BoxStats& t = m.steady_state_time;
    o << ',' << general(t.median) << ',' << general(t.median_low) << ',' << general(t.median_high) << ',' << general(t.q1) << ',' << general(t.q3)
      << ',' << general(m.final_delta.median * U) << ',' << general(m.final_delta_dot.median * U) << ','
      << general(p.final_phi_mean * U) << ',' << general(p.final_phi_sd * U) << '\n';
  }
}

// axis_tests.csv: one row per line of the grid.
void write_axis_tests_csv(const fs::path& dir, const StudyAnalysis& st, std::vector<std::string>& written) {
  ReportFile file(dir / "axis_tests.csv", written);
  std::ostream& o = file.out();
  o << "axis,fixed,points,kruskal_wallis_H,kruskal_wallis_df,kruskal_wallis_n,kruskal_wallis_p,friedman_chi2,"
       "friedman_df,friedman_blocks,friedman_p,d_median_first[mm*s^-1/2],d_median_last[mm*s^-1/2]\n";
  for (const AxisSlice& l : st.slices) {
    std::string pts;
    for (std::size_t p : l.points) pts += (pts.empty() ? "" : ";") + std::to_string(p);
    const auto& k = l.kruskal_wallis;
    const auto& f = l.friedman;
    o << column_name(st.axes[l.axis].key) << ',' << fixed_text(st, l, ";", "=") << ',' << pts << ',' << general(k.statistic)
      << ',' << k.df << ',' << k.n << ',' << general(k.p_value) << ',' << general(f.statistic) << ',' << f.df << ',' << f.n << ','
      << general(f.p_value) << ',' << general(st.points[l.points.front()].stats.center_distance.median * U) << ','
      << general(st.points[l.points.back()].stats.center_distance.median * U) << '\n';
  }
}

std::string interval_text(const Interval& i, int decimals) {
  return "[" + fixed(i.lo * U, decimals) + ", " + fixed(i.hi * U, decimals) + "]";
}

// report.md's head: the folders, the run counts, the grid and the units.
void write_study_head(std::ostream& r, const BatchInputs& in, const StudyAnalysis& st, const AnalysisSettings& s,
                      const std::string& pct) {
  r << "# gear_dynamics study report\n\nBatch folder(s): ";
  for (std::size_t i = 0; i < in.folders.size(); ++i) r << (i ? ", " : "") << "`" << in.folders[i] << "`";
  r << "\n\nT = " << in.config.run.duration << " s, h = " << in.config.run.time_step * 1e6 << " µs, window ["
    << in.config.run.duration - in.config.run.window << ", " << in.config.run.duration << "] s, seed " << in.config.seed
    << ". Runs used: " << in.runs.size() << " of " << in.expected_runs << " listed; bags skipped: " << in.skipped.size()
    << "; runs missing: " << in.missing.size() << ".\n\n";
  r << "The grid is the product of these axes (" << st.points.size() << " points); every point has S1, its phase "
       "ensemble (if the batch has one) and the same stochastic realizations: realization r has the same load path "
       "(the same normals) at every point (common random numbers).\n\n| axis | values |\n|---|---|\n";
  for (const SweepAxis& a : st.axes) {
    r << "| `" << a.key << "` |";
    for (std::size_t i = 0; i < a.values.size(); ++i)
      r << (i ? ", " : " ") << (a.text() ? a.value_text(a.values[i]) : general(a.values[i], 6));
    r << " |\n";
  }
  r << "\nUnits: d in mm·s^-1/2, t_ss in s. Medians with their exact " << pct
    << " order-statistic interval, probabilities in % with " << pct << " Wilson intervals. δ(T) ∈ "
    << interval_text(s.delta_interval, 4) << " mm, δ̇(T) ∈ " << interval_text(s.delta_dot_interval, 1)
    << " mm/s (closed). Every number is also in points.csv (one row per point) and axis_tests.csv (one row per line "
       "of the grid below).\n";
}

// report.md's sections: for every line of the grid, its sentence and its table.
void write_study_axes(std::ostream& r, const StudyAnalysis& st, const AnalysisSettings& s, const std::string& pct) {
  for (std::size_t axis = 0; axis < st.axes.size(); ++axis) {
    const std::string& key = st.axes[axis].key;
    if (st.axes[axis].values.size() < 2) continue;
    r << "\n## Along `" << key << "`\n";
    for (const AxisSlice& l : st.slices) {
      if (l.axis != axis) continue;
      const std::string others = fixed_text(st, l, ", ", " = ");
      const PointAnalysis &first = st.points[l.points.front()], &last = st.points[l.points.back()];
      r << "\n### `" << key << "`" << (others.empty() ? "" : " at " + others) << "\n\n";
      r << "Median d goes from " << median_ci(first.stats.center_distance, U, 3) << " at " << column_name(key) << " = "
 << axis_value(st, axis, first.values[axis], 6) << " to " << median_ci(last.stats.center_distance, U, 3) << " at "
        << axis_value(st, axis, last.values[axis], 6) << " mm·s^-1/2. Friedman's test blocked by realization (the design's common "
        << "random numbers): χ² = " << (l.friedman.valid ? fixed(l.friedman.statistic, 2) : "–") << ", df = "
        << l.friedman.df << ", " << l.friedman.n << " realizations, " << p_text(l.friedman) << "; Kruskal–Wallis: H = "
        << (l.kruskal_wallis.valid ? fixed(l.kruskal_wallis.statistic, 2) : "–") << ", " << p_text(l.kruskal_wallis)
        << ". ";
      if (!l.friedman.valid) r << "The test is not defined here (too few realizations, or every d tied).\n\n";
      else if (l.friedman.p_value < 1 - s.confidence)
        r << "At the " << fixed(100 * (1 - s.confidence), 0) << " % level, `" << key << "` changes d.\n\n";
      else r << "The data do not show that `" << key << "` changes d (p ≥ " << fixed(1 - s.confidence, 2) << ").\n\n";
      r << "| " << column_name(key) << " | R | median d [" << pct << "] | d Q1–Q3 | phase median d | P(d > phase median) | "
           "P(δ ∈) | P(δ̇ ∈) | P(both ∈) | t_ss median [" << pct << "] | t_ss Q1–Q3 | P(t_ss < T) |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
      for (std::size_t p : l.points) {
        const PointAnalysis& pa = st.points[p];
        const MuAnalysis& m = pa.stats;
        const BoxStats& d = m.center_distance;
        const BoxStats& t = m.steady_state_time;
        r << "| " << axis_value(st, axis, pa.values[axis], 6) << " | " << d.n << " | " << median_ci(d, U, 3) << " | "
          << fixed(d.q1 * U, 3) << "–" << fixed(d.q3 * U, 3) << " | " << fixed(m.phase_center_distance.median * U, 3)
          << " | " << percent(m.d_exceeds_phase_median) << " | " << percent(m.delta_in_interval) << " | "
          << percent(m.delta_dot_in_interval) << " | " << percent(pa.both_in_interval) << " | " << median_ci(t, 1, 4)
          << " | " << fixed(t.q1, 4) << "–" << fixed(t.q3, 4) << " | " << percent(m.reached_steady_state) << " |\n";
      }
    }
  }
}

// report.md's tail: the sections from above, the figures, what was left out.
void write_study_tail(std::ostream& r, const BatchInputs& in, const StudyAnalysis& st, const std::string& sections) {
  std::vector<std::size_t> varied;
  for (std::size_t a = 0; a < st.axes.size(); ++a)
    if (st.axes[a].values.size() > 1) varied.push_back(a);
  r << sections;
  r << "\n## Figures\n\n";
  for (std::size_t a : varied)
    r << "- `axis_" << column_name(st.axes[a].key) << ".png`: median d (with its interval), P(d > phase median) and "
         "P(δ ∈ ∧ δ̇ ∈) along `" << st.axes[a].key << "`, one line per value of the other axes.\n";
  if (varied.size() == 2)
    r << "- `heatmap_d.png`, `heatmap_both_in.png`: median d and P(δ(T) ∈ ∧ δ̇(T) ∈) over the 2-D grid.\n";
  if (!in.skipped.empty() || !in.missing.empty()) {
    r << "\n## Left out\n\n| item | status | reason |\n|---|---|---|\n";
    for (const SkippedFile& f : in.skipped) r << "| `" << f.file << "` | skipped | " << f.reason << " |\n";
    for (const std::string& m : in.missing) r << "| " << m << " | missing | |\n";
  }
}

}  // namespace

void write_study_files(const std::string& folder, const BatchInputs& in, const StudyAnalysis& st,
                       const AnalysisSettings& s, std::vector<std::string>& written, const std::string& sections) {
  const fs::path dir(folder);
  write_points_csv(dir, st, written);
  write_axis_tests_csv(dir, st, written);
  if (!st.swept()) return;
  ReportFile file(dir / "report.md", written);
  std::ostream& r = file.out();
  const std::string pct = std::to_string(static_cast<int>(std::lround(100 * s.confidence))) + " %";
  write_study_head(r, in, st, s, pct);
  write_study_axes(r, st, s, pct);
  write_study_tail(r, in, st, sections);
}

}  // namespace gear_dynamics
