// The per-mu analysis and the report on synthetic run records whose statistics are known.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "gear_dynamics/analysis/batch_analysis.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/report/report.hpp"

namespace gd = gear_dynamics;
namespace fs = std::filesystem;

namespace {

gd::RunRecord record(gd::RunKind kind, double mu, std::uint32_t index, double d, double delta, double delta_dot) {
  gd::RunRecord r;
  r.kind = kind;
  r.mu = mu;
  r.index = index;
  r.name = std::string(gd::to_string(kind)) + std::to_string(index);
  r.center_distance = d;
  r.steady_state_time = 0.3 + 0.001 * index;
  r.steady_state_time_fine = 0.35 + 0.001 * index;
  r.reached_steady_state = index % 3 != 0;
  r.final_delta = delta;
  r.final_delta_dot = delta_dot;
  r.final_phi = 20.0;
  r.snapshot_times = {0.30, 0.33, 0.35, 0.36, 0.40};
  for (double t : r.snapshot_times) {
    r.snapshot_delta.push_back(delta * t / 0.4);
    r.snapshot_delta_dot.push_back(delta_dot - (0.4 - t));
  }
  return r;
}

// Two mu values; at each, S1, 8 phase runs and 12 realizations with known values.
std::vector<gd::RunRecord> synthetic() {
  std::vector<gd::RunRecord> runs;
  for (double mu : {0.04, 0.0}) {  // out of order on purpose
    const double shift = mu * 10;
    runs.push_back(record(gd::RunKind::S1, mu, 0, 0.0005 + shift * 1e-3, 5.1e-5, -0.002));
    for (std::uint32_t j = 0; j < 8; ++j)
      runs.push_back(record(gd::RunKind::Phase, mu, j, 0.0002 + 0.0001 * j, 5.0e-5 + 1e-7 * j, 0.001 * j));
    for (std::uint32_t r = 0; r < 12; ++r)
      runs.push_back(record(gd::RunKind::Stochastic, mu, r, 0.0001 * (r + 1) + shift * 1e-4,
                            3.5e-5 + 2e-6 * r, -0.030 + 0.005 * r));
  }
  return runs;
}

}  // namespace

TEST(BatchAnalysis, PerMuStatisticsFromTheRecords) {
  const auto runs = synthetic();
  gd::AnalysisSettings s;
  const gd::BatchAnalysis a = gd::analyse(runs, s);
  ASSERT_EQ(a.mu.size(), 2u);
  EXPECT_EQ(a.mu[0].mu, 0.0);
  EXPECT_EQ(a.mu[1].mu, 0.04);
  for (const gd::MuAnalysis& m : a.mu) {
    std::vector<double> d;
    std::size_t above_s1 = 0, above_phase = 0, in_delta = 0, in_dot = 0, reached = 0;
    ASSERT_TRUE(m.s1);
    std::vector<double> phase_d;
    for (const auto& r : runs)
      if (r.mu == m.mu && r.kind == gd::RunKind::Phase) phase_d.push_back(r.center_distance);
    std::sort(phase_d.begin(), phase_d.end());
    const double phase_median = 0.5 * (phase_d[3] + phase_d[4]);  // n = 8
    for (const auto& r : runs) {
      if (r.mu != m.mu || r.kind != gd::RunKind::Stochastic) continue;
      d.push_back(r.center_distance);
      above_s1 += r.center_distance > m.s1->center_distance;
      above_phase += r.center_distance > phase_median;
      in_delta += r.final_delta >= 4.0e-5 && r.final_delta <= 5.5e-5;
      in_dot += r.final_delta_dot >= -0.016 && r.final_delta_dot <= 0.016;
      reached += r.reached_steady_state;
    }
    EXPECT_EQ(m.stochastic_runs, 12u);
    EXPECT_EQ(m.phase_runs, 8u);
    EXPECT_EQ(m.d_exceeds_s1.successes, above_s1);
    EXPECT_EQ(m.d_exceeds_s1.trials, 12u);
    EXPECT_DOUBLE_EQ(m.phase_center_distance.median, phase_median);
    EXPECT_EQ(m.d_exceeds_phase_median.successes, above_phase);
    EXPECT_EQ(m.delta_in_interval.successes, in_delta);
    EXPECT_EQ(m.delta_dot_in_interval.successes, in_dot);
    EXPECT_EQ(m.reached_steady_state.successes, reached);
    std::sort(d.begin(), d.end());
    EXPECT_DOUBLE_EQ(m.center_distance.min, d.front());
    EXPECT_DOUBLE_EQ(m.center_distance.median, 0.5 * (d[5] + d[6]));
    EXPECT_DOUBLE_EQ(*m.s2_center_distance, d[0]);  // realization 0 has the smallest d here
    EXPECT_DOUBLE_EQ(*m.s3_center_distance, d[1]);
    ASSERT_EQ(m.joint_pdf.size(), s.joint_times.size());
    for (const auto& h : m.joint_pdf) EXPECT_EQ(h.total, 12u);
    std::size_t hist_total = m.delta_pdf.outside;
    for (auto c : m.delta_pdf.counts) hist_total += c;
    EXPECT_EQ(hist_total, 12u);
  }
  // The synthetic d shifts by 4e-5 between the mu values at every realization: Friedman's test
  // sees 12 of 12 blocks ordered alike; Kruskal-Wallis sees two overlapping groups.
  EXPECT_EQ(a.friedman.n, 12u);
  EXPECT_NEAR(a.friedman.statistic, 12.0, 1e-12);  // sign test (12 - 0)^2 / 12
  EXPECT_TRUE(a.kruskal_wallis.valid);
  EXPECT_GT(a.kruskal_wallis.p_value, 0.3);
}

TEST(BatchAnalysis, StrictExceedanceAndClosedIntervals) {
  std::vector<gd::RunRecord> runs{record(gd::RunKind::S1, 0.02, 0, 1.0, 0, 0)};
  // d equal to d_S1 does not count; values on the interval ends do.
  runs.push_back(record(gd::RunKind::Stochastic, 0.02, 0, 1.0, 4.0e-5, -0.016));
  runs.push_back(record(gd::RunKind::Stochastic, 0.02, 1, 1.5, 5.5e-5, 0.016));
  runs.push_back(record(gd::RunKind::Stochastic, 0.02, 2, 0.5, 5.6e-5, 0.0161));
  const gd::BatchAnalysis a = gd::analyse(runs, gd::AnalysisSettings{});
  const gd::MuAnalysis& m = a.mu.at(0);
  EXPECT_EQ(m.d_exceeds_s1.successes, 1u);
  EXPECT_EQ(m.delta_in_interval.successes, 2u);
  EXPECT_EQ(m.delta_dot_in_interval.successes, 2u);
  // No phase ensemble: the robust comparison has no trials.
  EXPECT_EQ(m.d_exceeds_phase_median.trials, 0u);
  EXPECT_TRUE(std::isnan(m.d_exceeds_phase_median.estimate));
  EXPECT_FALSE(a.friedman.valid);  // one mu only
}

TEST(BatchAnalysis, JointTimeMustBeASnapshotTime) {
  gd::AnalysisSettings s;
  s.joint_times = {0.31};
  try {
    gd::analyse({record(gd::RunKind::Stochastic, 0.0, 0, 1, 0, 0)}, s);
    FAIL() << "no error";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("analysis.joint_times: 0.31 s"), std::string::npos) << ex.what();
  }
}

TEST(Report, WritesTablesWithPaperValuesAndEveryCsv) {
  gd::BatchInputs in;
  in.folders = {"/tmp/batch"};
  in.runs = synthetic();
  in.expected_runs = in.runs.size() + 1;
  in.missing = {"mu0.0400_r00012"};
  in.skipped = {{"/tmp/batch/x.bag", "truncated, bag index missing"}};
  const gd::BatchAnalysis a = gd::analyse(in.runs, gd::AnalysisSettings{});
  const fs::path dir = fs::temp_directory_path() / ("gd_report_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const auto files = gd::write_report(dir.string(), in, a);
  for (const char* f : {"report.md", "batch.csv", "runs.csv", "box_stats.csv", "probabilities.csv", "table3.csv", "pdf_delta.csv",
                        "pdf_delta_dot.csv", "joint_pdf.csv", "pdf_outside.csv", "rank_tests.csv", "inputs.csv"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_EQ(files.size(), 12u);
  std::ifstream md(dir / "report.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("| 0.04 | 4/12 |"), std::string::npos) << "exceedance row at mu = 0.04";
  EXPECT_NE(text.find("| 93 |"), std::string::npos) << "the paper's 93 %";
  EXPECT_NE(text.find("0.0508"), std::string::npos) << "Table 3 value of the paper at mu = 0.04";
  EXPECT_NE(text.find("truncated, bag index missing"), std::string::npos);
  // The stochastic d median at mu = 0 in mm s^-1/2: realizations 6 and 7 -> (6.5e-4) * 1e3.
  std::ifstream box(dir / "box_stats.csv");
  std::string line;
  bool found = false;
  while (std::getline(box, line))
    if (line.rfind("0,stochastic,d,", 0) == 0) {
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      EXPECT_NEAR(std::stod(f.at(7)), 0.65, 1e-9);
      found = true;
    }
  EXPECT_TRUE(found);
  // Density in 1/mm integrates to 1 - outside over widths in mm.
  std::ifstream pdf(dir / "pdf_delta.csv");
  std::getline(pdf, line);
  double integral = 0;
  while (std::getline(pdf, line)) {
    std::vector<double> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(std::stod(x));
    if (f[0] == 0.0) integral += f[4] * (f[2] - f[1]);
  }
  EXPECT_NEAR(integral, 1.0 - a.mu[0].delta_pdf.fraction_outside(), 1e-9);
  fs::remove_all(dir);
}

// The safety intervals are the paper's for its load: the report warns, naming mu and the median,
// when the median of delta(T) or delta_dot(T) lies outside them, and is silent when both lie inside.
TEST(Report, WarnsWhenTheMedianIsOutsideTheSafetyIntervals) {
  gd::BatchInputs in;
  in.folders = {"/tmp/batch"};
  in.runs = synthetic();
  in.expected_runs = in.runs.size();
  const gd::BatchAnalysis plain = gd::analyse(in.runs, gd::AnalysisSettings{});
  // Intervals around every mu's medians (a margin of 1 um and 1 mm/s) and one just above them all.
  double d_lo = 1, d_hi = -1, v_lo = 1e9, v_hi = -1e9;
  for (const gd::MuAnalysis& m : plain.mu) {
    d_lo = std::min(d_lo, m.final_delta.median), d_hi = std::max(d_hi, m.final_delta.median);
    v_lo = std::min(v_lo, m.final_delta_dot.median), v_hi = std::max(v_hi, m.final_delta_dot.median);
  }
  const auto report_with = [&](gd::Interval delta, gd::Interval delta_dot) {
    gd::AnalysisSettings s;
    s.delta_interval = delta;
    s.delta_dot_interval = delta_dot;
    const gd::BatchAnalysis a = gd::analyse(in.runs, s);
    const fs::path dir = fs::temp_directory_path() / ("gd_interval_test_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    gd::write_report(dir.string(), in, a);
    std::ifstream md(dir / "report.md");
    const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
    fs::remove_all(dir);
    return text;
  };
  const std::string inside = report_with({d_lo - 1e-6, d_hi + 1e-6}, {v_lo - 1e-3, v_hi + 1e-3});
  EXPECT_EQ(inside.find("safety intervals look off"), std::string::npos);
  const std::string above = report_with({d_hi + 1e-6, d_hi + 2e-6}, {v_lo - 1e-3, v_hi + 1e-3});
  EXPECT_NE(above.find("safety intervals look off"), std::string::npos);
  EXPECT_NE(above.find("median δ(T)"), std::string::npos);
  EXPECT_EQ(above.find("median δ̇(T)"), std::string::npos);
  const std::string slow = report_with({d_lo - 1e-6, d_hi + 1e-6}, {v_hi + 1e-3, v_hi + 2e-3});
  EXPECT_NE(slow.find("median δ̇(T)"), std::string::npos);
  EXPECT_EQ(slow.find("median δ(T)"), std::string::npos);
}
