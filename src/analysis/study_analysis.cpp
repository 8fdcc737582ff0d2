#include "gear_dynamics/analysis/study_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "gear_dynamics/analysis/report_text.hpp"

namespace gear_dynamics {

namespace {

using report_text::general;

}  // namespace

StudyAnalysis analyse_study(const BatchInputs& in, const AnalysisSettings& settings) {
  StudyAnalysis out;
  out.axes = in.axes;
  std::vector<std::vector<const RunRecord*>> by_point(in.points.size());
  for (const RunRecord& r : in.runs)
    if (r.point < by_point.size()) by_point[r.point].push_back(&r);
  for (std::size_t p = 0; p < in.points.size(); ++p) {
    PointAnalysis a;
    a.point = p;
    a.values = in.points[p];
    a.stats = analyse_group(a.values.at(0), by_point[p], settings);
    std::size_t both = 0, n = 0;
    double sum = 0, sum2 = 0;
    for (const RunRecord* r : by_point[p]) {
      if (r->kind != RunKind::Stochastic) continue;
      ++n;
      both += settings.delta_interval.contains(r->final_delta) && settings.delta_dot_interval.contains(r->final_delta_dot);
      sum += r->final_phi;
    }
    a.both_in_interval = wilson(both, n, settings.confidence);
    a.final_phi_mean = n ? sum / static_cast<double>(n) : std::nan("");
    for (const RunRecord* r : by_point[p])
      if (r->kind == RunKind::Stochastic) sum2 += (r->final_phi - a.final_phi_mean) * (r->final_phi - a.final_phi_mean);
    a.final_phi_sd = n > 1 ? std::sqrt(sum2 / static_cast<double>(n - 1)) : std::nan("");
    out.points.push_back(std::move(a));
  }

  // d of each stochastic realization at each point, for the tests.
  std::vector<std::map<std::uint32_t, double>> d(in.points.size());
  for (const RunRecord& r : in.runs)
    if (r.kind == RunKind::Stochastic && r.point < d.size()) d[r.point][r.index] = r.center_distance;

  // Lines of the grid: for each axis with > 1 value, points grouped by the values of the others.
  for (std::size_t axis = 0; axis < out.axes.size(); ++axis) {
    const std::vector<double>& values = out.axes[axis].values;
    if (values.size() < 2) continue;
    std::map<std::vector<double>, std::vector<std::size_t>> lines;
    std::vector<std::vector<double>> order;  // lines in the order of their first point
    for (std::size_t p = 0; p < in.points.size(); ++p) {
      std::vector<double> others = in.points[p];
      others[axis] = std::nan("");
      std::vector<double> k = others;
      k[axis] = 0;  // NaN never compares equal
      auto [it, inserted] = lines.emplace(k, std::vector<std::size_t>{});
      if (inserted) order.push_back(k);
      it->second.push_back(p);
    }
    for (const auto& k : order) {
      AxisSlice line;
      line.axis = axis;
      line.points = lines[k];
      const auto rank = [&](std::size_t p) {
        return std::find(values.begin(), values.end(), in.points[p][axis]) - values.begin();
      };
      std::stable_sort(line.points.begin(), line.points.end(), [&](std::size_t x, std::size_t y) { return rank(x) < rank(y); });
      line.fixed = k;
      line.fixed[axis] = std::nan("");
      std::vector<std::vector<double>> groups;
      for (std::size_t p : line.points) {
        groups.emplace_back();
        for (const auto& [r, x] : d[p]) groups.back().push_back(x);
      }
      line.kruskal_wallis = kruskal_wallis(groups);
      std::vector<std::vector<double>> blocks;  // realizations present at every point of the line
      for (const auto& [r, x] : d[line.points.front()]) {
        std::vector<double> row;
        for (std::size_t p : line.points) {
          const auto it = d[p].find(r);
          if (it == d[p].end()) break;
          row.push_back(it->second);
        }
        if (row.size() == line.points.size()) blocks.push_back(row);
      }
      line.friedman = friedman(blocks);
      out.slices.push_back(std::move(line));
    }
  }
  return out;
}

BatchAnalysis analyse_batch(const BatchInputs& in, const AnalysisSettings& settings, StudyAnalysis& study) {
  study = analyse_study(in, settings);
  if (!study.swept()) return analyse(in.runs, settings);
  BatchAnalysis out;
  out.settings = settings;
  out.key_header = "point";
  for (const SweepAxis& a : study.axes) out.key_header += "," + column_name(a.key);
  std::vector<std::vector<double>> groups;
  std::map<std::uint32_t, std::vector<double>> rows;
  for (const PointAnalysis& p : study.points) {
    out.mu.push_back(p.stats);
    std::string k = std::to_string(p.point);
    for (std::size_t a = 0; a < p.values.size(); ++a)
      k += "," + (study.axes[a].text() ? study.axes[a].value_text(p.values[a]) : general(p.values[a]));
    out.keys.push_back(k);
    groups.emplace_back();
  }
  for (const RunRecord& r : in.runs)
    if (r.kind == RunKind::Stochastic && r.point < groups.size()) {
      groups[r.point].push_back(r.center_distance);
      rows[r.index].resize(groups.size(), std::nan(""));
      rows[r.index][r.point] = r.center_distance;
    }
  out.kruskal_wallis = kruskal_wallis(groups);
  std::vector<std::vector<double>> blocks;
  for (const auto& [r, row] : rows)
    if (std::none_of(row.begin(), row.end(), [](double x) { return std::isnan(x); })) blocks.push_back(row);
  out.friedman = friedman(blocks);
  return out;
}

}  // namespace gear_dynamics
