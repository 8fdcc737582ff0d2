#include "gear_dynamics/ros/report_message.hpp"

#include <ros/time.h>

#include <limits>

namespace gear_dynamics {

namespace {

BoxPlot box_plot(const BoxStats& b) {
  BoxPlot m;
  m.n = static_cast<std::uint32_t>(b.n);
  m.min = b.min;
  m.q1 = b.q1;
  m.median = b.median;
  m.q3 = b.q3;
  m.max = b.max;
  m.median_low = b.median_low;
  m.median_high = b.median_high;
  m.median_coverage = b.median_coverage;
  return m;
}

ProbabilityInterval probability(const Proportion& p) {
  ProbabilityInterval m;
  m.successes = static_cast<std::uint32_t>(p.successes);
  m.trials = static_cast<std::uint32_t>(p.trials);
  m.estimate = p.estimate;
  m.low = p.low;
  m.high = p.high;
  return m;
}

DensityHistogram density(const Histogram& h) {
  DensityHistogram m;
  m.edges = h.edges;
  for (std::size_t i = 0; i < h.counts.size(); ++i) {
    m.counts.push_back(static_cast<std::uint32_t>(h.counts[i]));
    m.density.push_back(h.density(i));
  }
  m.outside = static_cast<std::uint32_t>(h.outside);
  m.total = static_cast<std::uint32_t>(h.total);
  return m;
}

JointDensity joint(const Histogram2D& h, double time) {
  JointDensity m;
  m.time = time;
  m.delta_edges = h.x_edges;
  m.delta_dot_edges = h.y_edges;
  const std::size_t ny = h.y_edges.size() - 1;
  for (std::size_t k = 0; k < h.counts.size(); ++k) {
    m.counts.push_back(static_cast<std::uint32_t>(h.counts[k]));
    m.density.push_back(h.density(k / ny, k % ny));
  }
  m.outside = static_cast<std::uint32_t>(h.outside);
  m.total = static_cast<std::uint32_t>(h.total);
  return m;
}

RankTestResult rank_test(const RankTest& t) {
  RankTestResult m;
  m.statistic = t.statistic;
  m.df = static_cast<std::uint32_t>(t.df);
  m.n = static_cast<std::uint32_t>(t.n);
  m.p_value = t.p_value;
  m.valid = t.valid;
  return m;
}

}  // namespace

BatchReport make_report_message(const BatchInputs& in, const BatchAnalysis& a, const std::string& report_folder) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  BatchReport m;
  m.header.stamp = ros::Time::now();
  m.folders = in.folders;
  m.report_folder = report_folder;
  m.confidence = a.settings.confidence;
  m.delta_interval = {a.settings.delta_interval.lo, a.settings.delta_interval.hi};
  m.delta_dot_interval = {a.settings.delta_dot_interval.lo, a.settings.delta_dot_interval.hi};
  m.runs_expected = static_cast<std::uint32_t>(in.expected_runs);
  m.runs_used = static_cast<std::uint32_t>(in.runs.size());
  for (const SkippedFile& s : in.skipped) {
    m.skipped_files.push_back(s.file);
    m.skipped_reasons.push_back(s.reason);
  }
  m.missing_runs = in.missing;
  for (const MuAnalysis& x : a.mu) {
    FrictionReport f;
    f.mu = x.mu;
    f.stochastic_runs = static_cast<std::uint32_t>(x.stochastic_runs);
    f.phase_runs = static_cast<std::uint32_t>(x.phase_runs);
    f.has_s1 = x.s1.has_value();
    f.s1_center_distance = x.s1 ? x.s1->center_distance : kNaN;
    f.s1_final_delta = x.s1 ? x.s1->final_delta : kNaN;
    f.s1_final_delta_dot = x.s1 ? x.s1->final_delta_dot : kNaN;
    f.s1_steady_state_time = x.s1 ? x.s1->steady_state_time : kNaN;
    f.s2_center_distance = x.s2_center_distance.value_or(kNaN);
    f.s3_center_distance = x.s3_center_distance.value_or(kNaN);
    f.center_distance = box_plot(x.center_distance);
    f.steady_state_time = box_plot(x.steady_state_time);
    f.steady_state_time_fine = box_plot(x.steady_state_time_fine);
    f.final_delta = box_plot(x.final_delta);
    f.final_delta_dot = box_plot(x.final_delta_dot);
    f.d_exceeds_s1 = probability(x.d_exceeds_s1);
    f.d_exceeds_phase_median = probability(x.d_exceeds_phase_median);
    f.reached_steady_state = probability(x.reached_steady_state);
    f.delta_in_interval = probability(x.delta_in_interval);
    f.delta_dot_in_interval = probability(x.delta_dot_in_interval);
    f.delta_pdf = density(x.delta_pdf);
    f.delta_dot_pdf = density(x.delta_dot_pdf);
    for (std::size_t k = 0; k < x.joint_pdf.size(); ++k) f.joint_pdf.push_back(joint(x.joint_pdf[k], a.settings.joint_times[k]));
    f.phase_center_distance = box_plot(x.phase_center_distance);
    f.phase_steady_state_time = box_plot(x.phase_steady_state_time);
    f.phase_final_delta = box_plot(x.phase_final_delta);
    f.phase_final_delta_dot = box_plot(x.phase_final_delta_dot);
    m.friction.push_back(f);
  }
  m.kruskal_wallis = rank_test(a.kruskal_wallis);
  m.friedman = rank_test(a.friedman);
  return m;
}

}  // namespace gear_dynamics
