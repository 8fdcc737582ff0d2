#include "gear_dynamics/maths/safety.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <boost/math/distributions/normal.hpp>

namespace gear_dynamics {

SafetySeries safety_over_time(const RecordedRuns& runs, const Interval& di, const Interval& vi, double confidence) {
  SafetySeries s;
  s.time = runs.time;
  const std::size_t R = runs.delta.size();
  if (runs.velocity.size() != R) throw std::invalid_argument("safety_over_time: delta and velocity differ in runs");
  for (std::size_t j = 0; j < runs.time.size(); ++j) {
    std::size_t both = 0, d = 0, v = 0;
    for (std::size_t r = 0; r < R; ++r) {
      const bool a = di.contains(runs.delta[r].at(j)), b = vi.contains(runs.velocity[r].at(j));
      both += a && b;
      d += a;
      v += b;
    }
    s.joint.push_back(wilson(both, R, confidence));
    s.delta_only.push_back(wilson(d, R, confidence));
    s.velocity_only.push_back(wilson(v, R, confidence));
  }
  return s;
}

FirstPassage first_passage(const RecordedRuns& runs, const Interval& di, const Interval& vi, double settle) {
  FirstPassage f;
  for (std::size_t r = 0; r < runs.delta.size(); ++r) {
    bool hit = false;
    double t = runs.time.empty() ? 0.0 : runs.time.back();
    for (std::size_t j = 0; j < runs.time.size(); ++j) {
      if (runs.time[j] < settle) continue;
      if (!(di.contains(runs.delta[r][j]) && vi.contains(runs.velocity[r][j]))) {
        hit = true;
        t = runs.time[j];
        break;
      }
    }
    f.time.push_back(t);
    f.event.push_back(hit);
  }
  return f;
}

KaplanMeier kaplan_meier(const std::vector<double>& time, const std::vector<bool>& event, double confidence) {
  if (time.size() != event.size()) throw std::invalid_argument("kaplan_meier: one event flag per time");
  std::vector<std::size_t> order(time.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return time[a] < time[b]; });
  const double z = boost::math::quantile(boost::math::normal(), 0.5 + 0.5 * confidence);
  KaplanMeier km;
  std::size_t at_risk = time.size(), i = 0;
  double s = 1.0, greenwood = 0.0;
  while (i < order.size()) {
    const double t = time[order[i]];
    std::size_t d = 0, leaving = 0;
    while (i < order.size() && time[order[i]] == t) {
      d += event[order[i]] ? 1 : 0;
      ++leaving;
      ++i;
    }
    if (d > 0) {
      const double n = static_cast<double>(at_risk);
      s *= 1.0 - static_cast<double>(d) / n;
      if (at_risk > d) greenwood += static_cast<double>(d) / (n * (n - static_cast<double>(d)));
      km.time.push_back(t);
      km.survival.push_back(s);
      km.at_risk.push_back(at_risk);
      km.events.push_back(d);
      if (s > 0 && s < 1) {
        const double se = std::sqrt(greenwood) / std::abs(std::log(s));
        const double c = std::log(-std::log(s));
        km.low.push_back(std::exp(-std::exp(c + z * se)));
        km.high.push_back(std::exp(-std::exp(c - z * se)));
      } else {
        km.low.push_back(s);
        km.high.push_back(s > 0 ? 1.0 : 0.0);
      }
    }
    at_risk -= leaving;
  }
  return km;
}

double survival_at(const KaplanMeier& km, double t) {
  double s = 1.0;
  for (std::size_t i = 0; i < km.time.size() && km.time[i] <= t; ++i) s = km.survival[i];
  return s;
}

double silverman_bandwidth(const std::vector<double>& values) {
  const std::size_t n = values.size();
  if (n < 2) throw std::invalid_argument("silverman_bandwidth: needs at least two values");
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(n);
  double ss = 0;
  for (double v : values) ss += (v - mean) * (v - mean);
  const double sd = std::sqrt(ss / static_cast<double>(n - 1));
  std::vector<double> s = values;
  std::sort(s.begin(), s.end());
  const double iqr = quantile_sorted(s, 0.75) - quantile_sorted(s, 0.25);
  double a = iqr > 0 ? std::min(sd, iqr / 1.34) : sd;
  if (!(a > 0)) a = std::max(std::abs(mean), 1.0) * 1e-6;  // all values equal: a narrow spike
  return 0.9 * a * std::pow(static_cast<double>(n), -0.2);
}

std::vector<double> gaussian_kde(const std::vector<double>& values, const std::vector<double>& grid, double bw) {
  if (values.empty()) throw std::invalid_argument("gaussian_kde: no values");
  if (!(bw > 0)) bw = silverman_bandwidth(values);
  const double norm = 1.0 / (static_cast<double>(values.size()) * bw * std::sqrt(2.0 * M_PI));
  std::vector<double> out(grid.size(), 0.0);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    double s = 0;
    for (double v : values) {
      const double u = (grid[i] - v) / bw;
      s += std::exp(-0.5 * u * u);
    }
    out[i] = s * norm;
  }
  return out;
}

}  // namespace gear_dynamics
