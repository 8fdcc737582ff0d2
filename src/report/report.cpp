#include "gear_dynamics/report/report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/analysis/report_text.hpp"
#include "gear_dynamics/report/paper_reference.hpp"
#include "gear_dynamics/report/report_file.hpp"
#include "sections.hpp"

namespace gear_dynamics {

namespace fs = std::filesystem;

namespace {

using report_text::fixed;
using report_text::general;
using report_text::percent;

constexpr double U = kToPaperUnits;

// A CSV field that may hold commas or quotes (RFC 4180).
std::string quoted(const std::string& text) {
  std::string q = "\"";
  for (char ch : text) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

// The paper's Table 4 only applies to its own intervals.
bool paper_intervals(const AnalysisSettings& s) {
  const auto same = [](double a, double b) { return std::abs(a - b) <= 1e-12; };
  return same(s.delta_interval.lo, 4.0e-5) && same(s.delta_interval.hi, 5.5e-5) &&
         same(s.delta_dot_interval.lo, -0.016) && same(s.delta_dot_interval.hi, 0.016);
}

std::string inside(double paper, const Proportion& p) {
  if (std::isnan(paper) || p.trials == 0) return "";
  return paper >= p.low && paper <= p.high ? "yes" : "no";
}

const char* kBoxHeader = "n,min,q1,median,q3,max,median_low,median_high,median_coverage";

void box_row(ReportFile& csv, const std::string& mu, const char* group, const char* quantity, const char* unit, const BoxStats& b,
             double scale) {
  csv.row(mu, group, quantity, unit, b.n, b.min * scale, b.q1 * scale, b.median * scale, b.q3 * scale,
          b.max * scale, b.median_low * scale, b.median_high * scale, b.median_coverage);
}

void probability_row(ReportFile& csv, const std::string& mu, const char* quantity, const std::string& reference, const Proportion& p,
                     double paper) {
  csv.row(mu, quantity, reference, p.successes, p.trials, p.estimate, p.low, p.high, paper, inside(paper, p));
}

std::string interval_text(const Interval& i, int decimals) {
  return "[" + fixed(i.lo * U, decimals) + ", " + fixed(i.hi * U, decimals) + "]";
}

std::string median_with_interval(const BoxStats& b, int decimals) {
  if (b.n == 0) return "–";
  return fixed(b.median * U, decimals) + " [" + fixed(b.median_low * U, decimals) + ", " + fixed(b.median_high * U, decimals) + "]";
}

double optional_value(const std::optional<double>& v) { return v ? *v : std::nan(""); }

// What every file of the report is written from, and the list of the files written so far.
struct ReportFiles {
  fs::path dir;
  const BatchInputs& in;
  const BatchAnalysis& a;
  const AnalysisSettings& s;
  bool paper_table4;  // the paper's Table 4 applies (its own intervals)
  std::string kh;     // row keys: mu for the mu sweep (format 1), else the point and its values
  std::string pct;    // the confidence, "95 %"
  std::vector<std::string>& written;

  std::string key(const MuAnalysis& m) const {
    return a.keys.empty() ? general(m.mu) : a.keys.at(static_cast<std::size_t>(&m - a.mu.data()));
  }

  void write_batch_csv() const;
  void write_runs_csv() const;
  void write_box_stats_csv() const;
  void write_probabilities_csv() const;
  void write_table3_csv() const;
  void write_pdfs_csv() const;
  void write_rank_tests_csv() const;
  void write_inputs_csv() const;
  void md_heading(std::ostream& r) const;
  void md_center_distance(std::ostream& r) const;
  void md_exceeds(std::ostream& r) const;
  void md_rank_tests(std::ostream& r) const;
  void md_table3(std::ostream& r) const;
  void md_table4(std::ostream& r) const;
  void md_interval_warning(std::ostream& r) const;
  void md_steady_state(std::ostream& r) const;
  void md_pdfs(std::ostream& r) const;
  void md_figures(std::ostream& r) const;
  void md_left_out(std::ostream& r) const;
};

// batch.csv: the batch's settings and how many runs it used.
void ReportFiles::write_batch_csv() const {
  ReportFile c(dir / "batch.csv", written, "key,value,unit");
  c.row("duration", in.config.run.duration, "s");
  c.row("time_step", in.config.run.time_step, "s");
  c.row("window", in.config.run.window, "s");
  c.row("seed", in.config.seed, "");
  c.row("confidence", s.confidence, "");
  c.row("runs_expected", in.expected_runs, "");
  c.row("runs_used", in.runs.size(), "");
  c.row("bags_skipped", in.skipped.size(), "");
  c.row("missing", in.missing.size(), "");
}

// runs.csv: one row per run used.
void ReportFiles::write_runs_csv() const {
  ReportFile c(dir / "runs.csv", written,
               "name,kind,mu,index,d[mm*s^-1/2],t_ss[s],t_ss_fine[s],reached_steady_state,delta_T[mm],"
               "delta_dot_T[mm/s],phi_T[mm/s^2]");
  for (const RunRecord& r : in.runs)
    c.row(r.name, to_string(r.kind), r.mu, r.index, r.center_distance * U, r.steady_state_time,
          r.steady_state_time_fine, r.reached_steady_state ? 1 : 0, r.final_delta * U, r.final_delta_dot * U,
          r.final_phi * U);
}

// box_stats.csv: the box statistics of every quantity per group.
void ReportFiles::write_box_stats_csv() const {
  ReportFile c(dir / "box_stats.csv", written, kh + ",group,quantity,unit," + kBoxHeader);
  for (const MuAnalysis& m : a.mu) {
    box_row(c, key(m), "stochastic", "d", "mm*s^-1/2", m.center_distance, U);
    box_row(c, key(m), "stochastic", "t_ss", "s", m.steady_state_time, 1);
    box_row(c, key(m), "stochastic", "t_ss_fine", "s", m.steady_state_time_fine, 1);
    box_row(c, key(m), "stochastic", "delta_T", "mm", m.final_delta, U);
    box_row(c, key(m), "stochastic", "delta_dot_T", "mm/s", m.final_delta_dot, U);
    box_row(c, key(m), "phase", "d", "mm*s^-1/2", m.phase_center_distance, U);
    box_row(c, key(m), "phase", "t_ss", "s", m.phase_steady_state_time, 1);
    box_row(c, key(m), "phase", "delta_T", "mm", m.phase_final_delta, U);
    box_row(c, key(m), "phase", "delta_dot_T", "mm/s", m.phase_final_delta_dot, U);
  }
}

// probabilities.csv: the Wilson intervals, with the paper's values where it has them.
void ReportFiles::write_probabilities_csv() const {
  ReportFile c(dir / "probabilities.csv", written,
               kh + ",quantity,reference,successes,trials,estimate,wilson_low,wilson_high,paper,paper_in_interval");
  for (const MuAnalysis& m : a.mu) {
    const PaperReference* p = a.keys.empty() ? paper_at(m.mu) : nullptr;  // a study's points are not the paper's
    const double nan = std::nan("");
    const double p93 = p && std::abs(m.mu - kPaperMuExceeds) < 1e-9 ? kPaperExceedsS1 : nan;
    probability_row(c, key(m), "d>d_S1", m.s1 ? general(m.s1->center_distance * U) + " mm*s^-1/2" : "no S1",
                    m.d_exceeds_s1, p93);
    probability_row(c, key(m), "d>median_phase_d", general(m.phase_center_distance.median * U) + " mm*s^-1/2",
                    m.d_exceeds_phase_median, nan);
    probability_row(c, key(m), "delta_T_in", interval_text(s.delta_interval, 4) + " mm", m.delta_in_interval,
                    p && paper_table4 ? p->p_delta / 100 : nan);
    probability_row(c, key(m), "delta_dot_T_in", interval_text(s.delta_dot_interval, 1) + " mm/s",
                    m.delta_dot_in_interval, p && paper_table4 ? p->p_delta_dot / 100 : nan);
    probability_row(c, key(m), "t_ss<T", "T = " + general(in.config.run.duration) + " s", m.reached_steady_state, nan);
  }
}

// table3.csv: S1, S2, S3 beside the paper's Table 3.
void ReportFiles::write_table3_csv() const {
  ReportFile c(dir / "table3.csv", written,
               kh + ",s1_delta_T[mm],paper_delta_T[mm],s1_delta_dot_T[mm/s],paper_delta_dot_T[mm/s],s1_d[mm*s^-1/2],"
               "s2_d[mm*s^-1/2],s3_d[mm*s^-1/2],s1_t_ss[s]");
  for (const MuAnalysis& m : a.mu) {
    const PaperReference* p = a.keys.empty() ? paper_at(m.mu) : nullptr;
    const double nan = std::nan("");
    c.row(key(m), m.s1 ? m.s1->final_delta * U : nan, p ? p->delta_T : nan, m.s1 ? m.s1->final_delta_dot * U : nan,
          p ? p->delta_dot_T : nan, m.s1 ? m.s1->center_distance * U : nan, optional_value(m.s2_center_distance) * U,
          optional_value(m.s3_center_distance) * U, m.s1 ? m.s1->steady_state_time : nan);
  }
}

// pdf_delta.csv, pdf_delta_dot.csv, joint_pdf.csv, pdf_outside.csv: the histograms at T and over time.
void ReportFiles::write_pdfs_csv() const {
  ReportFile cd(dir / "pdf_delta.csv", written, kh + ",lo[mm],hi[mm],count,density[1/mm]");
  ReportFile cv(dir / "pdf_delta_dot.csv", written, kh + ",lo[mm/s],hi[mm/s],count,density[s/mm]");
  ReportFile cj(dir / "joint_pdf.csv", written,
                kh + ",t[s],delta_lo[mm],delta_hi[mm],delta_dot_lo[mm/s],delta_dot_hi[mm/s],count,density[s/mm^2]");
  ReportFile co(dir / "pdf_outside.csv", written, kh + ",quantity,t[s],outside,total,fraction");
  for (const MuAnalysis& m : a.mu) {
    for (std::size_t i = 0; i < m.delta_pdf.counts.size(); ++i)
      cd.row(key(m), m.delta_pdf.edges[i] * U, m.delta_pdf.edges[i + 1] * U, m.delta_pdf.counts[i],
             m.delta_pdf.density(i) / U);
    for (std::size_t i = 0; i < m.delta_dot_pdf.counts.size(); ++i)
      cv.row(key(m), m.delta_dot_pdf.edges[i] * U, m.delta_dot_pdf.edges[i + 1] * U, m.delta_dot_pdf.counts[i],
             m.delta_dot_pdf.density(i) / U);
    const double T = in.config.run.duration;
    co.row(key(m), "delta_T", T, m.delta_pdf.outside, m.delta_pdf.total, m.delta_pdf.fraction_outside());
    co.row(key(m), "delta_dot_T", T, m.delta_dot_pdf.outside, m.delta_dot_pdf.total, m.delta_dot_pdf.fraction_outside());
    for (std::size_t k = 0; k < m.joint_pdf.size(); ++k) {
      const Histogram2D& h = m.joint_pdf[k];
      const std::size_t ny = h.y_edges.size() - 1;
      for (std::size_t i = 0; i + 1 < h.x_edges.size(); ++i)
        for (std::size_t j = 0; j < ny; ++j)
          cj.row(key(m), s.joint_times[k], h.x_edges[i] * U, h.x_edges[i + 1] * U, h.y_edges[j] * U,
                 h.y_edges[j + 1] * U, h.counts[i * ny + j], h.density(i, j) / (U * U));
      co.row(key(m), "joint", s.joint_times[k], h.outside, h.total, h.fraction_outside());
    }
  }
}

// rank_tests.csv: Kruskal-Wallis and Friedman across the groups.
void ReportFiles::write_rank_tests_csv() const {
  ReportFile c(dir / "rank_tests.csv", written, "test,statistic,df,n,p_value,valid");
  c.row("kruskal_wallis", a.kruskal_wallis.statistic, a.kruskal_wallis.df, a.kruskal_wallis.n,
        a.kruskal_wallis.p_value, a.kruskal_wallis.valid ? 1 : 0);
  c.row("friedman", a.friedman.statistic, a.friedman.df, a.friedman.n, a.friedman.p_value, a.friedman.valid ? 1 : 0);
}

// inputs.csv: the bags skipped and the runs missing.
void ReportFiles::write_inputs_csv() const {
  ReportFile c(dir / "inputs.csv", written, "item,status,reason");
  for (const SkippedFile& f : in.skipped) c.row(quoted(f.file), "skipped", quoted(f.reason));
  for (const std::string& m : in.missing) c.row(quoted(m), "missing", "");
}

// report.md: The heading: folders, settings, runs used, units.
void ReportFiles::md_heading(std::ostream& r) const {
  r << "# gear_dynamics batch report\n\n";
  r << "Batch folder(s): ";
  for (std::size_t i = 0; i < in.folders.size(); ++i) r << (i ? ", " : "") << "`" << in.folders[i] << "`";
  r << "\n\nT = " << in.config.run.duration << " s, h = " << in.config.run.time_step * 1e6 << " µs, window ["
    << in.config.run.duration - in.config.run.window << ", " << in.config.run.duration << "] s, seed "
    << in.config.seed << ". Runs used: " << in.runs.size() << " of " << in.expected_runs << " listed; bags skipped: "
    << in.skipped.size() << "; runs missing: " << in.missing.size()
    << (in.skipped.empty() && in.missing.empty() ? "." : " (see the end of this report and inputs.csv).") << "\n\n";
  r << "Units as in the paper: δ in mm, δ̇ in mm/s, d in mm·s^-1/2. Intervals are " << pct
    << ": Wilson score intervals for probabilities, exact distribution-free order-statistic intervals for "
       "medians. Every number is also in the CSV files beside this report; the figures are drawn from them.\n\n";
}

// report.md: Center distance d over the window (Figs. 8, 9).
void ReportFiles::md_center_distance(std::ostream& r) const {
  r << "## Center distance d over the window (Figs. 8, 9)\n\n"
       "Stochastic realizations: box-plot statistics (whiskers min–max as in Fig. 9) and the median with its "
    << pct << " interval. S1 is the deterministic run, S2 and S3 are realizations 0 and 1. The phase ensemble is "
       "S1 repeated over 64 initial mesh phases (doc/model.md §6). The paper gives d only at μ = 0.04: "
       "S1 0.34, S2 0.44, S3 0.59.\n\n";
  r << "| μ | R | min [mm·s^-1/2] | Q1 [mm·s^-1/2] | median [" << pct << "] [mm·s^-1/2] | Q3 [mm·s^-1/2] | max [mm·s^-1/2] "
       "| d S1 [mm·s^-1/2] | d S2 | d S3 | phase ensemble median [" << pct << "] (n) [mm·s^-1/2] |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MuAnalysis& m : a.mu) {
    const BoxStats& b = m.center_distance;
    r << "| " << fixed(m.mu, 2) << " | " << b.n << " | " << fixed(b.min * U, 3) << " | " << fixed(b.q1 * U, 3) << " | "
      << median_with_interval(b, 3) << " | " << fixed(b.q3 * U, 3) << " | " << fixed(b.max * U, 3) << " | "
      << (m.s1 ? fixed(m.s1->center_distance * U, 3) : "–") << " | " << fixed(optional_value(m.s2_center_distance) * U, 3)
      << " | " << fixed(optional_value(m.s3_center_distance) * U, 3) << " | "
      << median_with_interval(m.phase_center_distance, 3) << " (" << m.phase_runs << ") |\n";
  }
}

// report.md: P(d_stoch > d_det), the paper's 93 % statement.
void ReportFiles::md_exceeds(std::ostream& r) const {
  r << "\n## P(d_stoch > d_det) (the paper's 93 % statement)\n\n"
       "Strict inequality. Against S1 as in the paper, and, because one deterministic trajectory is not "
       "reproducible pathwise after about 0.1 s (doc/model.md §6), against the median d of the phase ensemble. "
       "The interval covers the sampling of the realizations only, not the uncertainty of the reference.\n\n";
  r << "| μ | d > d_S1: k/R | P [" << pct << "] (%) | paper (%) | paper inside? | d > phase median: k/R | P [" << pct
    << "] (%) |\n|---|---|---|---|---|---|---|\n";
  for (const MuAnalysis& m : a.mu) {
    const bool at_paper = std::abs(m.mu - kPaperMuExceeds) < 1e-9;
    r << "| " << fixed(m.mu, 2) << " | " << m.d_exceeds_s1.successes << "/" << m.d_exceeds_s1.trials << " | "
      << percent(m.d_exceeds_s1) << " | " << (at_paper ? fixed(100 * kPaperExceedsS1, 0) : "–") << " | "
      << (at_paper ? inside(kPaperExceedsS1, m.d_exceeds_s1) : "") << " | " << m.d_exceeds_phase_median.successes << "/"
      << m.d_exceeds_phase_median.trials << " | " << percent(m.d_exceeds_phase_median) << " |\n";
  }
}

// report.md: Whether d depends on mu: Kruskal-Wallis and Friedman.
void ReportFiles::md_rank_tests(std::ostream& r) const {
  r << "\n## Does d depend on μ?\n\n"
       "Kruskal–Wallis treats the μ groups as independent samples. The batch uses common random numbers "
       "(realization r has the same load path at every μ), so Friedman's test blocked by realization is the "
       "one that matches the design; both are reported. A large p-value means the data do not show a "
       "difference of d across μ.\n\n"
       "| test | statistic | df | n | p-value |\n|---|---|---|---|---|\n";
  for (const auto& [name, t] : {std::pair<const char*, const RankTest&>{"Kruskal–Wallis H", a.kruskal_wallis},
                                {"Friedman χ² (blocks = realizations)", a.friedman}}) {
    r << "| " << name << " | " << (t.valid ? fixed(t.statistic, 3) : "–") << " | " << t.df << " | " << t.n << " | ";
    if (!t.valid) r << "not defined (too few groups or blocks, or all tied)";
    else if (t.p_value < 1e-4) r << "< 1e-4";
    else r << fixed(t.p_value, 4);
    if (t.valid && t.exact) r << " (exact sign test)";
    r << " |\n";
  }
}

// report.md: Table 3 analogue: the responses at T under the deterministic load.
void ReportFiles::md_table3(std::ostream& r) const {
  r << "\n## Table 3 analogue: responses at T under the deterministic load\n\n"
       "S1's δ(T) and δ̇(T) beside the paper's. A single deterministic trajectory is not reproducible "
       "pathwise (doc/model.md §6), so the phase ensemble's median and range show what the model supports.\n\n"
       "| μ | S1 δ(T) [mm] | paper δ [mm] | phase δ(T) median [min, max] [mm] | S1 δ̇(T) [mm/s] | paper δ̇ [mm/s] | "
       "phase δ̇(T) median [min, max] [mm/s] |\n|---|---|---|---|---|---|---|\n";
  for (const MuAnalysis& m : a.mu) {
    const PaperReference* p = paper_at(m.mu);
    const BoxStats &pd = m.phase_final_delta, &pv = m.phase_final_delta_dot;
    r << "| " << fixed(m.mu, 2) << " | " << (m.s1 ? fixed(m.s1->final_delta * U, 4) : "–") << " | "
      << (p ? fixed(p->delta_T, 4) : "–") << " | " << fixed(pd.median * U, 4) << " [" << fixed(pd.min * U, 4) << ", "
      << fixed(pd.max * U, 4) << "] | " << (m.s1 ? fixed(m.s1->final_delta_dot * U, 3) : "–") << " | "
      << (p ? fixed(p->delta_dot_T, 3) : "–") << " | " << fixed(pv.median * U, 3) << " [" << fixed(pv.min * U, 3) << ", "
      << fixed(pv.max * U, 3) << "] |\n";
  }
}

// report.md: Table 4 analogue: the probabilities of the safety intervals at T.
void ReportFiles::md_table4(std::ostream& r) const {
  r << "\n## Table 4 analogue: probabilities of the safety intervals at T (%)\n\n"
    << "δ(T) ∈ " << interval_text(s.delta_interval, 4) << " mm and δ̇(T) ∈ " << interval_text(s.delta_dot_interval, 1)
    << " mm/s (closed)"
    << (paper_table4 ? ", the paper's intervals.\n\n" : "; the paper used [0.04, 0.055] mm and [-16, 16] mm/s, so its values are not shown.\n\n")
    << "| μ | P(δ ∈) [" << pct << "] (%) | paper (%) | paper inside? | P(δ̇ ∈) [" << pct
    << "] (%) | paper (%) | paper inside? |\n|---|---|---|---|---|---|---|\n";
  for (const MuAnalysis& m : a.mu) {
    const PaperReference* p = paper_table4 ? paper_at(m.mu) : nullptr;
    r << "| " << fixed(m.mu, 2) << " | " << percent(m.delta_in_interval) << " | " << (p ? fixed(p->p_delta, 0) : "–")
      << " | " << (p ? inside(p->p_delta / 100, m.delta_in_interval) : "") << " | " << percent(m.delta_dot_in_interval)
      << " | " << (p ? fixed(p->p_delta_dot, 0) : "–") << " | " << (p ? inside(p->p_delta_dot / 100, m.delta_dot_in_interval) : "")
      << " |\n";
  }
  md_interval_warning(r);
}

// report.md: the intervals are the paper's for its load by default; where the median of delta(T)
// or delta_dot(T) lies outside them, the probabilities say little about this load, and it is said.
void ReportFiles::md_interval_warning(std::ostream& r) const {
  std::string off;
  for (const MuAnalysis& m : a.mu) {
    if (m.stochastic_runs == 0) continue;
    const auto outside = [](double x, const auto& iv) { return x < iv.lo || x > iv.hi; };
    if (outside(m.final_delta.median, s.delta_interval))
      off += "\n- μ = " + fixed(m.mu, 2) + ": median δ(T) = " + fixed(m.final_delta.median * U, 4) + " mm, outside " +
             interval_text(s.delta_interval, 4) + " mm";
    if (outside(m.final_delta_dot.median, s.delta_dot_interval))
      off += "\n- μ = " + fixed(m.mu, 2) + ": median δ̇(T) = " + fixed(m.final_delta_dot.median * U, 3) +
             " mm/s, outside " + interval_text(s.delta_dot_interval, 1) + " mm/s";
  }
  if (!off.empty())
    r << "\n**Warning: the safety intervals look off for this run's load.** The medians below lie outside "
         "them, so these probabilities measure the distance from the intervals rather than the safety of this "
         "load; set `analysis.delta_interval` and `analysis.delta_dot_interval` for it (the aggregator's "
         "`config` overlay, or config/aggregator.yaml):\n"
      << off << "\n";
}

// report.md: Time to steady state t_ss.
void ReportFiles::md_steady_state(std::ostream& r) const {
  r << "\n## Time to steady state t_ss\n\n"
       "The last time |δ − b| exceeds " << in.config.run.steady_state_tolerance << "·b (doc/model.md §8). The paper "
       "reports about 0.35 s for S1 and that S2 and S3 had not settled by 0.4 s.\n\n"
       "| μ | S1 t_ss [s] | phase median [min, max] [s] | stochastic median [" << pct << "] [s] | stochastic Q1–Q3 [s] "
       "| P(t_ss < T) [" << pct << "] (%) |\n|---|---|---|---|---|---|\n";
  for (const MuAnalysis& m : a.mu) {
    const BoxStats &ps = m.phase_steady_state_time, &st = m.steady_state_time;
    r << "| " << fixed(m.mu, 2) << " | " << (m.s1 ? fixed(m.s1->steady_state_time, 4) : "–") << " | " << fixed(ps.median, 4)
      << " [" << fixed(ps.min, 4) << ", " << fixed(ps.max, 4) << "] | "
      << (st.n ? fixed(st.median, 4) + " [" + fixed(st.median_low, 4) + ", " + fixed(st.median_high, 4) + "]" : "–")
      << " | " << fixed(st.q1, 4) << "–" << fixed(st.q3, 4) << " | " << percent(m.reached_steady_state) << " |\n";
  }
}

// report.md: PDFs at T: the fractions outside the edges (Figs. 10-12).
void ReportFiles::md_pdfs(std::ostream& r) const {
  r << "\n## PDFs at T and their joint evolution (Figs. 10–12)\n\n"
       "Density-normalised histograms, count/(R·width), with doc/model.md's edges; the fraction of the "
       "realizations outside the edges is not in any bin:\n\n| μ | δ(T) outside (%) | δ̇(T) outside (%) |\n|---|---|---|\n";
  for (const MuAnalysis& m : a.mu)
    r << "| " << fixed(m.mu, 2) << " | " << fixed(100 * m.delta_pdf.fraction_outside(), 1) << " | "
      << fixed(100 * m.delta_dot_pdf.fraction_outside(), 1) << " |\n";
}

// report.md: The figures' table (Figs. 5-12).
void ReportFiles::md_figures(std::ostream& r) const {
  r << "\n## Figures\n\n"
       "| paper | figure |\n|---|---|\n"
       "| Fig. 5 load processes S1, S2, S3 | ![](fig05_load.png) |\n"
       "| Fig. 6 δ(t) of S1, S2, S3 | ![](fig06_delta.png) |\n"
       "| Fig. 7 phase portraits on the window | ![](fig07_phase.png) |\n"
       "| Fig. 8 d of S1, S2, S3 vs μ | ![](fig08_center_distance.png) |\n"
       "| Fig. 9 box plots of d vs μ | ![](fig09_boxplot.png) |\n"
       "| Fig. 10 joint PDF evolution | ![](fig10_joint_pdf.png) |\n"
       "| Fig. 11 PDF of δ(T) | ![](fig11_pdf_delta.png) |\n"
       "| Fig. 12 PDF of δ̇(T) | ![](fig12_pdf_delta_dot.png) |\n";
}

// report.md: What was left out (skipped bags, missing runs), if anything.
void ReportFiles::md_left_out(std::ostream& r) const {
  if (!in.skipped.empty() || !in.missing.empty()) {
    r << "\n## Left out\n\n| item | status | reason |\n|---|---|---|\n";
    for (const SkippedFile& f : in.skipped) r << "| `" << f.file << "` | skipped | " << f.reason << " |\n";
    for (const std::string& m : in.missing) r << "| " << m << " | missing | |\n";
  }
}

// gear_pair.model = bearings: bearing_forces.csv, one row per run and force (the window's mean and
// RMS), and the report.md section of their statistics over each group's runs [N]. "" and no file
// for a batch of the torsional model.
std::string write_bearing_forces(const fs::path& dir, const BatchInputs& in, const BatchAnalysis& a,
                                 std::vector<std::string>& written) {
  const bool any = std::any_of(in.runs.begin(), in.runs.end(), [](const RunRecord& r) { return r.bearings.has_value(); });
  if (!any) return "";
  const std::vector<BearingsOutputSpec> forces = bearing_force_outputs();
  const std::string kh = a.key_header.empty() ? "mu" : a.key_header;
  const auto key = [&](const RunRecord& r) { return r.point < a.keys.size() ? a.keys[r.point] : general(r.mu); };
  {
    ReportFile c(dir / "bearing_forces.csv", written, "name,kind," + kh + ",force,mean[N],rms[N]");
    for (const RunRecord& r : in.runs) {
      if (!r.bearings) continue;
      for (const BearingsOutputSpec& o : forces) {
        const ForceStatistics& f = (*r.bearings).*o.window;
        c.row(r.name, to_string(r.kind), key(r), o.name, f.mean, f.rms);
      }
    }
  }
  // Per group (mu or study point, in the order met) and force: the runs' mean of the window means,
  // and the mean, sd, min and max of their RMS.
  std::vector<std::size_t> order;
  std::map<std::size_t, std::vector<const RunRecord*>> groups;
  for (const RunRecord& r : in.runs) {
    if (!r.bearings) continue;
    if (groups.find(r.point) == groups.end()) order.push_back(r.point);
    groups[r.point].push_back(&r);
  }
  std::ostringstream md;
  md << "\n## Bearing forces (gear_pair.model: bearings)\n\n"
     << "Over the window [T − W, T] of each run: the mesh force F_m and the force each body puts on its bearing, x "
        "across the line of action and y along it (frames `pinion_bearing`, `wheel_bearing`; doc/model.md §11). "
        "Mean of the runs' window means; mean ± sd [min, max] of their RMS, in N. Per run: "
        "`bearing_forces.csv`.\n\n| " << kh << " | runs | force | mean | RMS |\n|---|---|---|---|---|\n";
  for (std::size_t point : order) {
    const std::vector<const RunRecord*>& runs = groups[point];
    const double n = static_cast<double>(runs.size());
    for (const BearingsOutputSpec& o : forces) {
      double mean = 0, rms = 0, rms2 = 0, lo = INFINITY, hi = -INFINITY;
      for (const RunRecord* r : runs) {
        const ForceStatistics f = (*r->bearings).*o.window;
        mean += f.mean / n, rms += f.rms / n, rms2 += f.rms * f.rms;
        lo = std::min(lo, f.rms), hi = std::max(hi, f.rms);
      }
      const double sd = runs.size() > 1 ? std::sqrt(std::max(0.0, (rms2 - n * rms * rms) / (n - 1))) : 0.0;
      md << "| " << key(*runs.front()) << " | " << runs.size() << " | " << o.name << " | " << general(mean) << " | "
         << general(rms) << " ± " << general(sd) << " [" << general(lo) << ", " << general(hi) << "] |\n";
    }
  }
  return md.str();
}

void write_report_md(const ReportFiles& R, const std::string& sections) {
  ReportFile file(R.dir / "report.md", R.written);
  std::ostream& r = file.out();
  R.md_heading(r);
  R.md_center_distance(r);
  R.md_exceeds(r);
  R.md_rank_tests(r);
  R.md_table3(r);
  R.md_table4(r);
  R.md_steady_state(r);
  R.md_pdfs(r);
  r << sections;  // the analyses over time
  R.md_figures(r);
  R.md_left_out(r);
}

}  // namespace

std::vector<std::string> write_report(const std::string& folder, const BatchInputs& in, const BatchAnalysis& a,
                                      const StudyAnalysis* study, const BatchOverTime* over_time) {
  const fs::path dir(folder);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create report folder " + folder + ": " + ec.message());
  std::vector<std::string> written;
  const std::string sections = (over_time ? write_over_time(folder, in, a, *over_time, written) : "") +
                               write_bearing_forces(dir, in, a, written);
  const AnalysisSettings& s = a.settings;
  const ReportFiles files{dir, in, a, s, paper_intervals(s), a.key_header.empty() ? "mu" : a.key_header,
                          std::to_string(static_cast<int>(std::lround(100 * s.confidence))) + " %", written};
  files.write_batch_csv();
  files.write_runs_csv();
  files.write_box_stats_csv();
  files.write_probabilities_csv();
  files.write_table3_csv();
  files.write_pdfs_csv();
  files.write_rank_tests_csv();
  files.write_inputs_csv();
  if (study) write_study_files(folder, in, *study, s, written, sections);
  if (study && study->swept()) return written;  // its report.md is organised by axis
  write_report_md(files, sections);
  return written;
}

}  // namespace gear_dynamics
