// The report's files on synthetic run records whose statistics are known.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "gear_dynamics/analysis/batch_analysis.hpp"
#include "gear_dynamics/report/report.hpp"
#include "run_records.hpp"

namespace gd = gear_dynamics;
namespace fs = std::filesystem;
using gear_dynamics::test::synthetic;

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
