// The detection study's statistics against closed forms, the probability of detection against
// crack depth on a small study, and the monitor over a recorded series against the simulated
// windows (doc/monitor_study.md).
#include <gtest/gtest.h>

#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <random>
#include <set>

#include "gear_dynamics/monitor/study.hpp"

namespace gd = gear_dynamics;

namespace {

gd::ModelConfig cracked_config(double load) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  YAML::Node root = gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"});
  root["gear_pair"]["mesh_stiffness"] = "potential_energy";
  root["gear_pair"]["crack_gear"] = "pinion";
  root["gear_pair"]["crack_tooth"] = 0;
  root["load"]["initial_mean"] = load;
  return gd::parse_config(root);
}

// The trapezoidal area under an empirical ROC: an independent computation of the Mann-Whitney AUC.
double trapezoid_area(const std::vector<gd::RocPoint>& roc) {
  double area = 0;
  for (std::size_t i = 1; i < roc.size(); ++i)
    area += (roc[i].false_positive - roc[i - 1].false_positive) * 0.5 *
            (roc[i].true_positive + roc[i - 1].true_positive);
  return area;
}

}  // namespace

// A hand-made sample: of the 6 (positive, negative) pairs, 2 > {1}, 2 = {2} (a half), 4 > all three:
// U = 4.5, AUC 0.75. Its ROC's trapezoids give the same area, ties and all.
TEST(MonitorStudy, AucIsMannWhitneyOnAHandMadeSample) {
  const std::vector<double> negatives{3, 1, 2}, positives{4, 2};
  EXPECT_DOUBLE_EQ(gd::area_under_roc(negatives, positives), 0.75);
  const auto roc = gd::roc_curve(negatives, positives);
  ASSERT_EQ(roc.size(), 5u);  // +inf, 4, 3, 2, 1
  EXPECT_DOUBLE_EQ(roc.back().false_positive, 1.0);
  EXPECT_DOUBLE_EQ(roc.back().true_positive, 1.0);
  EXPECT_DOUBLE_EQ(trapezoid_area(roc), 0.75);
  EXPECT_DOUBLE_EQ(gd::area_under_roc(positives, negatives), 0.25);
  EXPECT_THROW(gd::area_under_roc({}, positives), std::invalid_argument);
}

// Two normal samples N(0, 1) and N(d, 1): AUC = Phi(d / sqrt 2). The tolerance is 4 of Hanley &
// McNeil's (1982) standard errors of an AUC estimated from these sample sizes.
TEST(MonitorStudy, AucOfTwoNormalSamples) {
  const boost::math::normal normal;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> z;
  const int n = 2000;
  for (double d : {0.0, 0.5, 1.0, 2.0}) {
    std::vector<double> neg(n), pos(n);
    for (auto& x : neg) x = z(rng);
    for (auto& x : pos) x = d + z(rng);
    const double a = boost::math::cdf(normal, d / std::sqrt(2.0));
    const double q1 = a / (2 - a), q2 = 2 * a * a / (1 + a);
    const double se = std::sqrt((a * (1 - a) + (n - 1) * (q1 - a * a) + (n - 1) * (q2 - a * a)) / (double(n) * n));
    const double auc = gd::area_under_roc(neg, pos);
    EXPECT_NEAR(auc, a, 4 * se) << "d = " << d;
    EXPECT_NEAR(trapezoid_area(gd::roc_curve(neg, pos)), auc, 1e-12);
  }
}

// Clopper-Pearson at the ends has closed forms: 0 of n has the upper bound 1 - (tail)^(1/n), n of n
// the lower bound tail^(1/n). Hence MIL-HDBK-1823A's "29 of 29": 0.05^(1/29) = 0.9019 >= 0.9, while
// 28 of 28 gives 0.8984 < 0.9.
TEST(MonitorStudy, ClopperPearsonClosedForms) {
  EXPECT_NEAR(gd::clopper_pearson(0, 10).high, 1 - std::pow(0.025, 0.1), 1e-12);
  EXPECT_NEAR(gd::clopper_pearson(10, 10).low, std::pow(0.025, 0.1), 1e-12);
  EXPECT_NEAR(gd::clopper_pearson_lower(29, 29), std::pow(0.05, 1.0 / 29), 1e-12);
  EXPECT_GE(gd::clopper_pearson_lower(29, 29), 0.9);
  EXPECT_LT(gd::clopper_pearson_lower(28, 28), 0.9);
  // Inside: the interval holds the estimate and the one-sided bound lies above the two-sided one.
  const auto p = gd::clopper_pearson(30, 100);
  EXPECT_LT(p.low, 0.3);
  EXPECT_GT(p.high, 0.3);
  EXPECT_GT(gd::clopper_pearson_lower(30, 100), p.low);
  EXPECT_THROW(gd::clopper_pearson(5, 4), std::invalid_argument);

  // a90/95: the smallest depth from which on the lower bound stays >= 0.9.
  std::vector<gd::DetectionSummary> rows(4);
  const double depth[] = {0.5e-3, 1e-3, 1.5e-3, 2e-3}, bound[] = {0.95, 0.5, 0.91, 0.92};
  for (int i = 0; i < 4; ++i) rows[i].load = 2000, rows[i].depth = depth[i], rows[i].detector = "fm4",
                              rows[i].pod_lower95 = bound[i];
  EXPECT_DOUBLE_EQ(gd::a90_95(rows, 2000, "fm4"), 1.5e-3);
  EXPECT_TRUE(std::isnan(gd::a90_95(rows, 2000, "rms")));
}

// A small study at a load where the teeth stay in contact: for T², the CUSUM and the indicators of
// the difference and residual signals, the probability of detection does not fall with depth by more than 3 standard errors of the difference of two
// binomial proportions (the healthy case is the false-alarm rate, near alpha). RMS and the crest
// factor are left out: they are not monotone in depth (doc/monitor_study.md). The deepest crack is
// detected by T² in most windows and the CUSUM alarms in most runs.
TEST(MonitorStudy, DetectionDoesNotFallWithDepth) {
  gd::StudySettings s;
  s.reference.realizations = 60;
  s.reference.windows = 2;
  s.reference.load_means = {2000.0};
  s.test_realizations = 24;
  s.first_test = 100000;
  s.crack_depths = {0.0, 0.25e-3, 1.0e-3, 2.0e-3};
  const auto result = gd::run_study(cracked_config(2000.0), s);
  ASSERT_EQ(result.cases.size(), 4u);
  const auto rows = gd::summarize(result);
  const auto names = gd::detector_names(result.reference);
  ASSERT_EQ(rows.size(), 4 * (names.size() + 1));
  const std::set<std::string> monotone = {"fm4", "m6a", "m8a", "na4", "na4_star", "t2", "cusum"};
  for (std::size_t d = 0; d <= names.size(); ++d)
    for (std::size_t c = 1; c < 4; ++c) {
      if (!monotone.count(rows[d].detector)) continue;
      const auto& shallow = rows[(c - 1) * (names.size() + 1) + d];
      const auto& deep = rows[c * (names.size() + 1) + d];
      ASSERT_EQ(shallow.detector, deep.detector);
      const double p1 = shallow.pod.estimate, p2 = deep.pod.estimate;
      // The variance at the pooled proportion, floored at one window's worth so 0 vs 0 is not zero.
      const double p = std::max(0.5 * (p1 + p2), 1.0 / deep.windows);
      const double se = std::sqrt(p * (1 - p) * (1.0 / shallow.windows + 1.0 / deep.windows));
      EXPECT_GE(p2, p1 - 3 * se) << deep.detector << " from " << shallow.depth << " to " << deep.depth << " m";
    }
  const auto& t2_deepest = rows[3 * (names.size() + 1) + names.size() - 1];
  ASSERT_EQ(t2_deepest.detector, "t2");
  EXPECT_GT(t2_deepest.pod.estimate, 0.9);
  EXPECT_GT(t2_deepest.auc, 0.9);
  const auto& cusum_deepest = rows.back();
  ASSERT_EQ(cusum_deepest.detector, "cusum");
  EXPECT_GT(cusum_deepest.runs_detected, cusum_deepest.runs / 2);

  s.first_test = 30;  // inside the reference's streams 0 .. 59
  EXPECT_THROW(gd::validate(s), std::invalid_argument);
}

// The monitor over a recorded series (what a bag or a batch folder holds: the signal, the shaft
// angle, the load) gives the windows and assessments of the simulated runs, sample for sample.
TEST(MonitorStudy, RecordedSeriesMatchesTheSimulatedWindows) {
  const gd::ModelConfig config = cracked_config(2000.0);
  gd::ReferenceSettings rs;
  rs.realizations = 40;
  rs.windows = 3;
  const gd::Reference ref = gd::build_reference(config, rs);
  const auto& m = ref.settings.monitor;
  const std::uint64_t stream = 777;

  // Record one lane as a recorder would: every decimation-th grid step after the warm-up.
  const gd::GearPair gear = gd::derive(config.gear);
  const double h = config.run.time_step;
  gd::Ensemble ensemble(gear, h, config.initial, {gd::stochastic_lane(config, config.friction_coefficient, stream)},
                        config.seed);
  std::vector<double> angle, value, load;
  const auto first = static_cast<std::int64_t>(std::floor(rs.warmup / h));
  const double t_end = rs.warmup + (rs.windows + 1.5) * gd::revolution_angle(gear, m.gear) / gear.in.pinion_speed;
  while (ensemble.time() < t_end) {
    ensemble.step();
    if (ensemble.step_index() < first || ensemble.step_index() % m.decimation != 0) continue;
    angle.push_back(gd::shaft_angle(gear, ensemble.time()));
    value.push_back(ensemble.padded_delta()(0));
    load.push_back(ensemble.load()(0));
  }
  const auto series = gd::monitor_series(ref, angle, value, load);
  const auto simulated = gd::simulate_windows(config, m, stream, 1, rs.warmup, rs.windows);
  ASSERT_GE(series.size(), static_cast<std::size_t>(rs.windows));
  gd::ConditionMonitor monitor(ref);
  for (int w = 0; w < rs.windows; ++w) {
    const auto expected = monitor.assess(simulated[0][w]);
    const auto& got = series[w].assessment;
    EXPECT_EQ(series[w].index, w);
    EXPECT_NEAR(got.load, expected.load, 1e-12 * std::abs(expected.load));
    EXPECT_NEAR(got.t2, expected.t2, 1e-9 * expected.t2);
    EXPECT_NEAR(got.cusum, expected.cusum, 1e-9 * (1 + expected.cusum));
    for (std::size_t i = 0; i < got.indicators.size(); ++i)
      EXPECT_NEAR(got.indicators[i], expected.indicators[i], 1e-9 * std::abs(expected.indicators[i]))
          << ref.indicators[i];
    EXPECT_EQ(got.health, expected.health);
  }
  EXPECT_THROW(gd::monitor_series(ref, angle, {1.0}), std::invalid_argument);
}
