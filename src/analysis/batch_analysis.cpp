#include "gear_dynamics/analysis/batch_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

namespace {

// Snapshot times and requested joint times are both whole multiples of h computed in double.
constexpr double kTimeMatch = 1e-9;  // [s]
constexpr double kInf = std::numeric_limits<double>::infinity();

std::size_t snapshot_index(const RunRecord& r, double t) {
  for (std::size_t k = 0; k < r.snapshot_times.size(); ++k)
    if (std::abs(r.snapshot_times[k] - t) <= kTimeMatch) return k;
  std::ostringstream e;
  e << "analysis.joint_times: " << t << " s is not among the snapshot times of run " << r.name << " (";
  for (std::size_t k = 0; k < r.snapshot_times.size(); ++k) e << (k ? ", " : "") << r.snapshot_times[k];
  e << " s); choose joint times from the batch's run.snapshot_times";
  throw std::invalid_argument(e.str());
}

template <class Pred>
Proportion count_if(const std::vector<double>& v, Pred pred, double confidence) {
  return wilson(static_cast<std::size_t>(std::count_if(v.begin(), v.end(), pred)), v.size(), confidence);
}

}  // namespace

MuAnalysis analyse_group(double mu, const std::vector<const RunRecord*>& runs, const AnalysisSettings& s) {
  MuAnalysis a;
  a.mu = mu;
  std::vector<double> d, tss, tss_fine, fd, fv, pd, ptss, pfd, pfv;
  std::vector<const RunRecord*> stochastic;
  std::size_t reached = 0;
  for (const RunRecord* r : runs) {
    switch (r->kind) {
      case RunKind::S1:
        if (!a.s1) a.s1 = *r;
        break;
      case RunKind::Phase:
        pd.push_back(r->center_distance);
        ptss.push_back(r->steady_state_time);
        pfd.push_back(r->final_delta);
        pfv.push_back(r->final_delta_dot);
        break;
      case RunKind::Stochastic:
        stochastic.push_back(r);
        d.push_back(r->center_distance);
        tss.push_back(r->steady_state_time);
        tss_fine.push_back(r->steady_state_time_fine);
        fd.push_back(r->final_delta);
        fv.push_back(r->final_delta_dot);
        reached += r->reached_steady_state ? 1 : 0;
        if (r->index == 0) a.s2_center_distance = r->center_distance;
        if (r->index == 1) a.s3_center_distance = r->center_distance;
        break;
    }
  }
  const double c = s.confidence;
  a.stochastic_runs = d.size();
  a.phase_runs = pd.size();
  a.center_distance = box_stats(d, c);
  a.steady_state_time = box_stats(tss, c);
  a.steady_state_time_fine = box_stats(tss_fine, c);
  a.final_delta = box_stats(fd, c);
  a.final_delta_dot = box_stats(fv, c);
  a.phase_center_distance = box_stats(pd, c);
  a.phase_steady_state_time = box_stats(ptss, c);
  a.phase_final_delta = box_stats(pfd, c);
  a.phase_final_delta_dot = box_stats(pfv, c);

  // Without its reference a comparison has no trials: estimate NaN, interval [0, 1].
  const std::vector<double> none;
  const double ds1 = a.s1 ? a.s1->center_distance : 0.0;
  a.d_exceeds_s1 = count_if(a.s1 ? d : none, [&](double x) { return x > ds1; }, c);
  const double dphase = a.phase_center_distance.median;
  a.d_exceeds_phase_median = count_if(pd.empty() ? none : d, [&](double x) { return x > dphase; }, c);
  a.reached_steady_state = wilson(reached, d.size(), c);
  a.delta_in_interval = count_if(fd, [&](double x) { return s.delta_interval.contains(x); }, c);
  a.delta_dot_in_interval = count_if(fv, [&](double x) { return s.delta_dot_interval.contains(x); }, c);
  a.delta_pdf = histogram(fd, s.delta_bins);
  a.delta_dot_pdf = histogram(fv, s.delta_dot_bins);

  for (double t : s.joint_times) {
    std::vector<double> x, y;
    for (const RunRecord* r : stochastic) {
      const std::size_t k = snapshot_index(*r, t);
      x.push_back(r->snapshot_delta.at(k));
      y.push_back(r->snapshot_delta_dot.at(k));
    }
    a.joint_pdf.push_back(histogram2d(x, y, s.joint_delta_bins, s.joint_delta_dot_bins));
  }
  return a;
}

BatchAnalysis analyse(const std::vector<RunRecord>& runs, const AnalysisSettings& settings) {
  BatchAnalysis out;
  out.settings = settings;
  std::map<double, std::vector<const RunRecord*>> by_mu;
  for (const RunRecord& r : runs) by_mu[r.mu].push_back(&r);

  std::vector<std::vector<double>> groups;
  std::map<std::uint32_t, std::vector<double>> by_realization;  // d at each mu, in mu order
  for (const auto& [mu, group] : by_mu) {
    out.mu.push_back(analyse_group(mu, group, settings));
    groups.emplace_back();
    for (const RunRecord* r : group) {
      if (r->kind != RunKind::Stochastic) continue;
      groups.back().push_back(r->center_distance);
      auto& row = by_realization[r->index];
      if (row.size() + 1 == groups.size()) row.push_back(r->center_distance);  // one per mu, in order
    }
  }
  out.kruskal_wallis = kruskal_wallis(groups);
  std::vector<std::vector<double>> blocks;  // realizations present at every mu with stochastic runs
  const auto with_runs = static_cast<std::size_t>(std::count_if(groups.begin(), groups.end(), [](const auto& g) { return !g.empty(); }));
  if (with_runs == groups.size())
    for (const auto& [r, row] : by_realization)
      if (row.size() == groups.size()) blocks.push_back(row);
  out.friedman = friedman(blocks);
  return out;
}

}  // namespace gear_dynamics
