// The detection study and the monitor over a recorded series (doc/monitor_study.md).
#include "gear_dynamics/monitor/study.hpp"

#include <boost/math/distributions/beta.hpp>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace gear_dynamics {

namespace {

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

void require_samples(const std::vector<double>& negatives, const std::vector<double>& positives) {
  if (negatives.empty() || positives.empty())
    throw std::invalid_argument("the ROC needs both samples: " + std::to_string(negatives.size()) + " negatives, " +
                                std::to_string(positives.size()) + " positives");
}

}  // namespace

double area_under_roc(const std::vector<double>& negatives, const std::vector<double>& positives) {
  require_samples(negatives, positives);
  // Mann-Whitney U from the mid-ranks of the pooled sample: O(n log n), ties counted as half.
  std::vector<std::pair<double, bool>> pooled;
  pooled.reserve(negatives.size() + positives.size());
  for (double x : negatives) pooled.emplace_back(x, false);
  for (double x : positives) pooled.emplace_back(x, true);
  std::sort(pooled.begin(), pooled.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  double rank_sum = 0.0;
  for (std::size_t i = 0; i < pooled.size();) {
    std::size_t j = i;
    while (j < pooled.size() && pooled[j].first == pooled[i].first) ++j;
    const double mid_rank = 0.5 * static_cast<double>(i + 1 + j);
    for (std::size_t m = i; m < j; ++m)
      if (pooled[m].second) rank_sum += mid_rank;
    i = j;
  }
  const double np = static_cast<double>(positives.size()), nn = static_cast<double>(negatives.size());
  return (rank_sum - np * (np + 1.0) / 2.0) / (np * nn);
}

std::vector<RocPoint> roc_curve(const std::vector<double>& negatives, const std::vector<double>& positives) {
  require_samples(negatives, positives);
  std::vector<double> neg = negatives, pos = positives, thresholds = negatives;
  std::sort(neg.begin(), neg.end());
  std::sort(pos.begin(), pos.end());
  thresholds.insert(thresholds.end(), positives.begin(), positives.end());
  std::sort(thresholds.begin(), thresholds.end(), std::greater<>());
  thresholds.erase(std::unique(thresholds.begin(), thresholds.end()), thresholds.end());
  const auto at_or_above = [](const std::vector<double>& sorted, double t) {
    return static_cast<double>(sorted.end() - std::lower_bound(sorted.begin(), sorted.end(), t)) /
           static_cast<double>(sorted.size());
  };
  std::vector<RocPoint> roc{{std::numeric_limits<double>::infinity(), 0.0, 0.0}};
  for (double t : thresholds) roc.push_back({t, at_or_above(neg, t), at_or_above(pos, t)});
  return roc;
}

ProportionInterval clopper_pearson(long k, long n, double confidence) {
  if (n <= 0 || k < 0 || k > n)
    throw std::invalid_argument("clopper_pearson: " + std::to_string(k) + " successes of " + std::to_string(n) +
                                " trials; allowed 0 <= successes <= trials, trials > 0");
  const double tail = 0.5 * (1.0 - confidence);
  ProportionInterval p;
  p.estimate = static_cast<double>(k) / static_cast<double>(n);
  p.low = k == 0 ? 0.0 : boost::math::quantile(boost::math::beta_distribution<>(k, n - k + 1.0), tail);
  p.high = k == n ? 1.0 : boost::math::quantile(boost::math::beta_distribution<>(k + 1.0, n - k), 1.0 - tail);
  return p;
}

double clopper_pearson_lower(long k, long n, double confidence) {
  return clopper_pearson(k, n, 1.0 - 2.0 * (1.0 - confidence)).low;
}

void validate(const StudySettings& s) {
  validate(s.reference);
  if (s.crack_depths.empty()) throw std::invalid_argument("monitor_study.crack_depths is empty; give at least one depth");
  for (double d : s.crack_depths)
    if (!(d >= 0.0))
      throw std::invalid_argument("monitor_study.crack_depths has " + std::to_string(d) + "; allowed depths >= 0 m");
  if (s.test_realizations < 2 || s.test_realizations > 1000000)
    throw std::invalid_argument("monitor_study.test_realizations = " + std::to_string(s.test_realizations) +
                                " is out of range; allowed [2, 1000000]");
  const std::uint64_t ref_end = s.reference.first_realization + static_cast<std::uint64_t>(s.reference.realizations);
  const std::uint64_t test_end = s.first_test + static_cast<std::uint64_t>(s.test_realizations);
  if (s.first_test < ref_end && s.reference.first_realization < test_end)
    throw std::invalid_argument("monitor_study.first_test = " + std::to_string(s.first_test) +
                                " overlaps the reference's streams [" + std::to_string(s.reference.first_realization) +
                                ", " + std::to_string(ref_end) + "); allowed: a disjoint range of streams");
}

std::vector<std::string> detector_names(const Reference& reference) {
  std::vector<std::string> names = reference.indicators;
  names.push_back("t2");
  return names;
}

double detector_value(const Assessment& a, std::size_t d) {
  return d < a.indicators.size() ? a.indicators[d] : a.t2;
}

bool detector_alarm(const Assessment& a, std::size_t d) {
  return d < a.indicators.size() ? a.exceeded[d] != 0 : a.t2_alarm;
}

StudyResult run_study(const ModelConfig& config, const StudySettings& settings) {
  validate(settings);
  if (config.gear.crack.gear == FaultyGear::kNone)
    throw std::invalid_argument("gear_pair.crack_gear = none: the study needs the crack's gear (pinion or wheel)");
  // Every depth checked before the reference's runs: a depth beyond the tooth's centre line is
  // refused at once, naming the key.
  for (double depth : settings.crack_depths) {
    ModelConfig at = config;
    at.gear.crack.depth = depth;
    validate_consistency(at);
  }
  StudyResult result;
  double t0 = cpu_seconds();
  result.reference = build_reference(config, settings.reference);
  result.cpu_reference = cpu_seconds() - t0;
  const GearPair gear = derive(config.gear);
  const auto& m = settings.reference.monitor;
  result.window_seconds = m.revolutions_per_window * revolution_angle(gear, m.gear) / gear.in.pinion_speed;
  for (const auto& band : result.reference.bands)
    for (double depth : settings.crack_depths) {
      ModelConfig at = config;
      at.load.initial_mean = band.load;
      at.gear.crack.depth = depth;
      t0 = cpu_seconds();
      const auto runs = simulate_windows(at, m, settings.first_test, settings.test_realizations,
                                         settings.reference.warmup, settings.reference.windows);
      result.cpu_simulation += cpu_seconds() - t0;
      StudyCase c;
      c.load = band.load;
      c.depth = depth;
      ConditionMonitor monitor(result.reference);
      t0 = cpu_seconds();
      for (const auto& run : runs) {
        monitor.reset();
        auto& out = c.runs.emplace_back();
        for (const auto& w : run) out.push_back(monitor.assess(w));
        result.windows_assessed += static_cast<long>(run.size());
      }
      result.cpu_assessment += cpu_seconds() - t0;
      result.cases.push_back(std::move(c));
    }
  return result;
}

namespace {

std::vector<double> values_of(const StudyCase& c, std::size_t d) {
  std::vector<double> v;
  for (const auto& run : c.runs)
    for (const auto& a : run) v.push_back(detector_value(a, d));
  return v;
}

const StudyCase* healthy_case(const StudyResult& r, double load) {
  for (const auto& c : r.cases)
    if (c.load == load && c.depth == 0.0) return &c;
  return nullptr;
}

}  // namespace

std::vector<DetectionSummary> summarize(const StudyResult& r) {
  const auto names = detector_names(r.reference);
  std::vector<DetectionSummary> rows;
  for (const auto& c : r.cases) {
    const StudyCase* healthy = healthy_case(r, c.load);
    for (std::size_t d = 0; d <= names.size(); ++d) {  // the last: the CUSUM
      const bool cusum = d == names.size();
      DetectionSummary s;
      s.load = c.load;
      s.depth = c.depth;
      s.detector = cusum ? "cusum" : names[d];
      s.auc = !cusum && healthy ? area_under_roc(values_of(*healthy, d), values_of(c, d))
                                : std::numeric_limits<double>::quiet_NaN();
      double delay = 0.0;
      for (const auto& run : c.runs) {
        int first = 0;
        for (std::size_t w = 0; w < run.size(); ++w) {
          const bool alarm = cusum ? run[w].cusum_alarm : detector_alarm(run[w], d);
          s.alarms += alarm;
          ++s.windows;
          if (alarm && first == 0) first = static_cast<int>(w) + 1;
        }
        ++s.runs;
        if (first > 0) ++s.runs_detected, delay += first;
      }
      s.mean_delay_windows = s.runs_detected ? delay / s.runs_detected : std::numeric_limits<double>::quiet_NaN();
      s.pod = clopper_pearson(s.alarms, s.windows);
      s.pod_lower95 = clopper_pearson_lower(s.alarms, s.windows);
      rows.push_back(std::move(s));
    }
  }
  return rows;
}

double a90_95(const std::vector<DetectionSummary>& rows, double load, const std::string& detector) {
  std::vector<std::pair<double, double>> bound;  // depth, lower bound
  for (const auto& r : rows)
    if (r.load == load && r.detector == detector && r.depth > 0.0) bound.emplace_back(r.depth, r.pod_lower95);
  std::sort(bound.begin(), bound.end());
  double a = std::numeric_limits<double>::quiet_NaN();
  for (auto it = bound.rbegin(); it != bound.rend() && it->second >= 0.9; ++it) a = it->first;
  return a;
}

void write_study_csv(const std::string& prefix, const StudyResult& result) {
  const auto open = [](const std::string& path) {
    std::ofstream f(path);
    if (!f) throw std::runtime_error("cannot write " + path);
    f.precision(10);
    return f;
  };
  const auto rows = summarize(result);
  {
    auto f = open(prefix + "_summary.csv");
    f << "load,depth,detector,auc,windows,alarms,pod,pod_low,pod_high,pod_lower95,runs,runs_detected,"
         "mean_delay_windows,mean_delay_seconds\n";
    for (const auto& r : rows)
      f << r.load << ',' << r.depth << ',' << r.detector << ',' << r.auc << ',' << r.windows << ',' << r.alarms << ','
        << r.pod.estimate << ',' << r.pod.low << ',' << r.pod.high << ',' << r.pod_lower95 << ',' << r.runs << ','
        << r.runs_detected << ',' << r.mean_delay_windows << ',' << r.mean_delay_windows * result.window_seconds
        << '\n';
  }
  const auto names = detector_names(result.reference);
  {
    auto f = open(prefix + "_roc.csv");
    f << "load,depth,detector,threshold,false_positive,true_positive\n";
    for (const auto& c : result.cases) {
      const StudyCase* healthy = healthy_case(result, c.load);
      if (!healthy || c.depth == 0.0) continue;
      for (std::size_t d = 0; d < names.size(); ++d)
        for (const auto& p : roc_curve(values_of(*healthy, d), values_of(c, d)))
          f << c.load << ',' << c.depth << ',' << names[d] << ',' << p.threshold << ',' << p.false_positive << ','
            << p.true_positive << '\n';
    }
  }
  {
    auto f = open(prefix + "_a9095.csv");
    f << "load,detector,a90_95\n";
    for (const auto& band : result.reference.bands)
      for (std::size_t d = 0; d <= names.size(); ++d) {
        const std::string name = d < names.size() ? names[d] : "cusum";
        f << band.load << ',' << name << ',' << a90_95(rows, band.load, name) << '\n';
      }
  }
}

std::vector<MonitoredWindow> monitor_series(const Reference& reference, const std::vector<double>& angle,
                                            const std::vector<double>& value, const std::vector<double>& load) {
  if (angle.size() != value.size() || (!load.empty() && load.size() != value.size()))
    throw std::invalid_argument("monitor_series: " + std::to_string(angle.size()) + " angles, " +
                                std::to_string(value.size()) + " values and " + std::to_string(load.size()) +
                                " loads; allowed: as many of each (no loads: the first band)");
  ConditionMonitor monitor(reference);
  const auto& m = monitor.settings();
  RevolutionWindows cut(monitor.revolution_angle(), m.revolutions_per_window, m.samples_per_revolution);
  const double default_load = reference.bands.empty() ? 0.0 : reference.bands.front().load;
  std::vector<MonitoredWindow> out;
  for (std::size_t i = 0; i < angle.size(); ++i)
    if (auto w = cut.add(angle[i], value[i], load.empty() ? default_load : load[i])) {
      MonitoredWindow mw;
      mw.index = static_cast<std::int64_t>(out.size());
      mw.start_angle = w->start_angle;
      mw.assessment = monitor.assess(*w);
      out.push_back(std::move(mw));
    }
  return out;
}

}  // namespace gear_dynamics
