// The healthy Monte Carlo reference (doc/monitor.md §4): the false-alarm rate on held-out streams
// against the nominal, the CUSUM's in-control run length, the file and its refusals.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <boost/math/distributions/normal.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/monitor/reference.hpp"

#include "paper_config.hpp"

namespace gd = gear_dynamics;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("gd_monitor_" + std::to_string(::getpid()) + "_" + name)).string();
}

// The Brook-Evans Markov chain of a one-sided CUSUM on N(0, 1) increments: S on m cells of
// [0, h], the in-control ARL from S = 0 (an independent computation of what Siegmund approximates).
template <class Cdf>
double markov_chain_arl(double k, double h, Cdf cdf, int m = 400) {
  const double w = 2.0 * h / (2.0 * m - 1.0);
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(m, m);
  for (int i = 0; i < m; ++i) {
    a(i, 0) -= cdf(w / 2 - i * w + k);
    for (int j = 1; j < m; ++j) a(i, j) -= cdf((j - i) * w + w / 2 + k) - cdf((j - i) * w - w / 2 + k);
  }
  return a.partialPivLu().solve(Eigen::VectorXd::Ones(m))(0);
}
double markov_chain_arl(double k, double h) {
  const boost::math::normal normal;
  return markov_chain_arl(k, h, [&](double x) { return boost::math::cdf(normal, x); });
}

gd::ReferenceSettings settings(int realizations, std::uint64_t first = 0) {
  gd::ReferenceSettings s;
  s.realizations = realizations;
  s.first_realization = first;
  s.windows = 1;  // one window per realization: the windows are independent
  s.warmup = 0.1;
  s.false_alarm = 0.05;
  return s;
}

}  // namespace

// The CUSUM's h comes from Siegmund's approximation; the Markov chain puts its in-control ARL
// within 1 % of the nominal for k = 0.5 (Siegmund's error there; the chain converged to 1e-5 at
// 400 cells), so 2 % fails on a wrong h or a wrong recursion.
TEST(MonitorReference, CusumInControlRunLength) {
  for (double arl : {50.0, 200.0, 500.0}) {
    const double h = gd::cusum_threshold_for(0.5, arl);
    EXPECT_NEAR(gd::siegmund_arl(0.5, h), arl, 1e-6 * arl);
    EXPECT_NEAR(markov_chain_arl(0.5, h) / arl, 1.0, 0.02) << "ARL " << arl << ", h " << h;
  }
  // Out of control by one sd the ARL falls to a handful of windows (Siegmund ~ 10 for ARL0 200).
  const double h = gd::cusum_threshold_for(0.5, 200.0);
  EXPECT_LT(gd::siegmund_arl(0.5, h, 1.0), 12.0);
}

// The reference from streams 0..1023 (one window each, the paper's gear at its light load under
// the stochastic load), applied to held-out streams 1024..2047: the fraction of windows above each
// threshold is the nominal 5 % within 3 standard deviations of binomial sampling, inflated for
// the reference's own (1 - alpha) quantile: sqrt(a (1 - a) (1 / n_test + 1 / n_ref)) = 0.0096.
// The held-out windows' normal scores are N(0, 1) within their sampling error, and the CUSUM on
// them runs as long as Siegmund's ARL for their distribution.
TEST(MonitorReference, FalseAlarmRateOnHeldOutStreams) {
  const gd::ModelConfig config = paper_config();
  const int n = 1024;
  const gd::Reference ref = gd::build_reference(config, settings(n));
  ASSERT_EQ(ref.bands.size(), 1u);
  const auto& band = ref.bands[0];
  EXPECT_EQ(band.windows, static_cast<std::size_t>(n));
  EXPECT_GT(band.rank, 3);

  const auto runs = gd::simulate_windows(config, ref.settings.monitor, n, n, 0.1, 1);
  gd::ConditionMonitor monitor(ref);
  std::vector<int> count(ref.indicators.size(), 0);
  int t2 = 0, total = 0;
  std::vector<double> scores;
  for (const auto& run : runs) {
    ASSERT_EQ(run.size(), 1u);
    monitor.reset();
    const auto a = monitor.assess(run[0]);
    t2 += a.t2_alarm;
    for (std::size_t i = 0; i < count.size(); ++i) count[i] += a.exceeded[i];
    scores.push_back(a.score);
    ++total;
  }
  const double alpha = 0.05, sd = std::sqrt(alpha * (1 - alpha) * (2.0 / n));
  std::printf("held-out false alarms at nominal %.3f: T2 %d of %d", alpha, t2, total);
  for (std::size_t i = 0; i < count.size(); ++i) std::printf(", %s %d", ref.indicators[i].c_str(), count[i]);
  std::printf("\n");
  EXPECT_NEAR(static_cast<double>(t2) / total, alpha, 3 * sd) << t2 << " of " << total;
  for (std::size_t i = 0; i < count.size(); ++i)
    EXPECT_NEAR(static_cast<double>(count[i]) / total, alpha, 3 * sd) << ref.indicators[i];

  // The held-out scores are N(0, 1) up to sampling: their mean has a standard error of
  // 1/sqrt(n) from the held-out sample and as much from the reference's ranks, 0.044 together.
  double mean = 0, ss = 0;
  for (double z : scores) mean += z;
  mean /= scores.size();
  for (double z : scores) ss += (z - mean) * (z - mean);
  const double sd_scores = std::sqrt(ss / (scores.size() - 1.0));
  EXPECT_NEAR(mean, 0.0, 3 * std::sqrt(2.0 / n));
  EXPECT_NEAR(sd_scores, 1.0, 0.1);  // 3 standard errors of an sd (1/sqrt(2n)) and the ranks' again
  // The CUSUM on them, fed in a random order (independent windows): its mean run length against
  // the Markov chain on their empirical distribution (2000 runs: a standard error of 2.2 %, so
  // 9 % is 4 of them), and that within Siegmund's ARL for a mean shifted by +-3 standard errors
  // of the scores' mean (the in-control ARL is steep in it: 0.03 sd moves it 16 %).
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<std::size_t> pick(0, scores.size() - 1);
  double sum = 0;
  const int runs_cusum = 2000;
  for (int r = 0; r < runs_cusum; ++r) {
    double s = 0;
    int length = 0;
    do {
      s = std::max(0.0, s + scores[pick(rng)] - ref.settings.cusum_reference);
      ++length;
    } while (s <= ref.cusum_threshold && length < 1000000);
    sum += length;
  }
  const double k = ref.settings.cusum_reference, h = ref.cusum_threshold;
  std::vector<double> sorted = scores;
  std::sort(sorted.begin(), sorted.end());
  const double chain = markov_chain_arl(k, h, [&](double x) {
    return static_cast<double>(std::upper_bound(sorted.begin(), sorted.end(), x) - sorted.begin()) / sorted.size();
  });
  const double shift = 3 * std::sqrt(2.0 / n);
  std::printf("held-out scores: mean %.4f, sd %.4f; CUSUM mean run length %.1f windows, Markov chain %.1f, "
              "nominal %.0f (Siegmund %.0f..%.0f for a mean within +-%.2f)\n",
              mean, sd_scores, sum / runs_cusum, chain, ref.settings.average_run_length,
              gd::siegmund_arl(k, h, shift), gd::siegmund_arl(k, h, -shift), shift);
  EXPECT_NEAR(sum / runs_cusum / chain, 1.0, 0.09);
  EXPECT_GT(chain, gd::siegmund_arl(k, h, shift));
  EXPECT_LT(chain, gd::siegmund_arl(k, h, -shift));
}

// The file: written and read back to the same numbers; refused for another gear by the key's name,
// accepted for the same gear with a crack (the fault is what is monitored); another format,
// another numbers generation or other indicators refused with the reason.
TEST(MonitorReference, FileRoundTripAndRefusals) {
  gd::ModelConfig config = paper_config();
  auto s = settings(20);
  s.false_alarm = 0.25;  // 20 windows: the 75 % quantile is inside the sample
  s.load_means = {20.0, 2000.0};
  s.warmup = 0.02;
  const gd::Reference ref = gd::build_reference(config, s);
  ASSERT_EQ(ref.bands.size(), 2u);
  EXPECT_EQ(ref.band_of(19.0), 0u);
  EXPECT_EQ(ref.band_of(1500.0), 1u);
  EXPECT_DOUBLE_EQ(ref.bands[0].load_high, 1010.0);
  // The bands are not interchangeable: at the light load the teeth rattle through the backlash
  // (2b = 100 um) and δ's RMS about its mean is microns, tens of times that of the loaded mesh.
  const std::size_t rms = gd::indicator_index("rms");
  EXPECT_GT(ref.bands[0].mean[rms], 10.0 * ref.bands[1].mean[rms]);

  const std::string path = temp_path("reference.yaml");
  gd::write_reference(path, ref);
  const gd::Reference back = gd::read_reference(path);
  EXPECT_EQ(gd::reference_text(back), gd::reference_text(ref));
  EXPECT_EQ(back.bands[1].t2, ref.bands[1].t2);
  EXPECT_EQ(back.bands[1].load_high, ref.bands[1].load_high);

  gd::ModelConfig cracked = config;
  cracked.gear.crack.gear = gd::FaultyGear::kPinion;
  cracked.gear.crack.depth = 1e-3;
  EXPECT_NO_THROW(gd::check_reference(back, cracked, path));
  gd::ModelConfig other = config;
  other.gear.backlash = 1e-4;
  try {
    gd::check_reference(back, other, path);
    FAIL() << "a reference for another backlash was accepted";
  } catch (const gd::ReferenceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("gear_pair.backlash"), std::string::npos) << what;
    EXPECT_NE(what.find(path), std::string::npos) << what;
  }

  const auto edited = [&](const std::string& from, const std::string& to) {
    std::string text = gd::reference_text(ref);
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    const std::string p = temp_path("edited.yaml");
    std::ofstream(p) << text;
    try {
      gd::read_reference(p);
    } catch (const gd::ReferenceError& e) {
      std::filesystem::remove(p);
      return std::string(e.what());
    }
    std::filesystem::remove(p);
    return std::string("accepted");
  };
  EXPECT_NE(edited("gear_dynamics_monitor_reference/1", "gear_dynamics_monitor_reference/9").find("format"),
            std::string::npos);
  EXPECT_NE(edited("numbers: " + std::to_string(gd::kNumbersGeneration), "numbers: 1").find("numbers generation 1"),
            std::string::npos);
  EXPECT_NE(edited("fm4", "fm5").find("lists the indicators"), std::string::npos);
  EXPECT_NE(edited("false_alarm: 0.25", "false_alarm: 0.75").find("monitor.false_alarm = 0.75"), std::string::npos);
  std::filesystem::remove(path);
}

// A window at a load the reference never saw is not judged (WARN, the CUSUM held): the live load
// wanders, and indicators at another load would otherwise drive the CUSUM to ERROR for good. The
// outer edges are the extreme loads of the reference's windows, so its own windows are all inside.
TEST(MonitorReference, LoadOutsideTheReferenceIsNotJudged) {
  gd::ModelConfig config = paper_config();
  auto s = settings(20);
  s.warmup = 0.02;
  s.false_alarm = 0.25;  // 20 windows: the 75 % quantile is inside the sample
  const gd::Reference ref = gd::build_reference(config, s);
  const auto own = gd::simulate_windows(config, ref.settings.monitor, 0, 20, s.warmup, 1);
  for (const auto& run : own) EXPECT_TRUE(ref.covers(run[0].mean_load)) << run[0].mean_load;
  EXPECT_LT(ref.bands[0].load_low, config.load.initial_mean);
  EXPECT_GT(ref.bands[0].load_high, config.load.initial_mean);

  gd::ModelConfig heavier = config;
  heavier.load.initial_mean = 3 * config.load.initial_mean;
  const auto far = gd::simulate_windows(heavier, ref.settings.monitor, 100, 1, s.warmup, 1);
  gd::ConditionMonitor monitor(ref);
  const gd::Assessment inside = monitor.assess(own[0][0]);
  EXPECT_TRUE(inside.in_reference);
  const gd::Assessment outside = monitor.assess(far[0][0]);
  EXPECT_FALSE(outside.in_reference);
  EXPECT_EQ(outside.health, gd::Health::kWarn);
  EXPECT_FALSE(outside.t2_alarm || outside.cusum_alarm);
  EXPECT_EQ(outside.cusum, inside.cusum);
}

TEST(MonitorReference, BadSettingsNameTheKey) {
  auto s = settings(10);
  s.false_alarm = 0.05;  // 10 windows cannot hold a 95 % quantile
  try {
    gd::validate(s);
    FAIL() << "10 windows at 5 % were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("monitor.realizations = 10"), std::string::npos) << e.what();
  }
  s = settings(100);
  s.monitor.gear = gd::FaultyGear::kNone;
  EXPECT_THROW(gd::validate(s), std::invalid_argument);
  EXPECT_THROW(gd::parse_monitored_signal("force"), std::invalid_argument);
}

namespace {

// The paper's gear on its bearings at a mean load where the teeth stay in contact.
gd::ModelConfig bearings_config(double mu) {
  gd::ModelConfig c = paper_config();
  c.gear.model = gd::GearModel::kBearings;
  c.load.initial_mean = 2000.0;
  c.friction_coefficient = mu;
  return c;
}

// The first window of one realization cut the way simulate_windows documents it, from a lane
// stepped here and each sample's outputs from the schedule at grid step n (the other overload of
// bearings_outputs: no mesh point shared between lanes).
gd::RevolutionWindow first_window_by_hand(const gd::ModelConfig& config, const gd::MonitorSettings& m,
                                          std::uint64_t realization, double warmup, double gd::BearingsOutputs::*force) {
  const gd::GearPair gear = gd::derive(config.gear);
  const double h = config.run.time_step;
  gd::Ensemble lane(gear, h, config.initial, {gd::stochastic_lane(config, config.friction_coefficient, realization)},
                    config.seed);
  gd::RevolutionWindows cut(gd::revolution_angle(gear, m.gear), m.revolutions_per_window, m.samples_per_revolution);
  const auto first = static_cast<std::int64_t>(std::floor(warmup / h));
  for (;;) {
    lane.step();
    const std::int64_t n = lane.step_index();
    if (n < first || n % m.decimation != 0) continue;
    const gd::BearingsModel::State y = lane.model_state().col(0);
    const double value = gd::bearings_outputs(*lane.bearings_model(), gear, lane.mesh(), h, n, y).*force;
    if (auto w = cut.add(gd::shaft_angle(gear, lane.time()), value, lane.load()(0))) return *w;
  }
}

double mean(const Eigen::VectorXd& v) { return v.mean(); }

}  // namespace

// Every name parses back to its signal; an unknown name, a bearing force of the torsional model,
// or a bearing force asked of a state are refused naming the key, the value and what is allowed.
TEST(MonitorSignals, TableAndRefusals) {
  for (const gd::MonitoredSignalSpec& s : gd::monitored_signals()) {
    EXPECT_EQ(gd::parse_monitored_signal(s.name), s.signal);
    EXPECT_EQ(&gd::signal_spec(s.signal), &s);
    EXPECT_EQ(s.bearing_force == nullptr, s.wrench_topic == nullptr) << s.name;
  }
  try {
    gd::parse_monitored_signal("force", "--signal");
    FAIL() << "force was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--signal = force"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("pinion_fy"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(gd::require_signal(gd::MonitoredSignal::kWheelFx, gd::GearModel::kBearings));
  EXPECT_NO_THROW(gd::require_signal(gd::MonitoredSignal::kMeshForce, gd::GearModel::kTorsional));
  gd::MonitorSettings m;
  m.signal = gd::MonitoredSignal::kPinionFy;
  try {
    gd::simulate_windows(paper_config(), m, 0, 1, 0.1, 1);
    FAIL() << "a bearing force of the torsional model was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("monitor.signal = pinion_fy"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gear_pair.model = bearings"), std::string::npos) << e.what();
  }
  // At mu = 0 nothing acts across the line of action: a reference on that constant is refused.
  auto s = settings(20);
  s.false_alarm = 0.25;
  s.warmup = 0.02;
  s.monitor.signal = gd::MonitoredSignal::kPinionFx;
  try {
    gd::build_reference(bearings_config(0.0), s);
    FAIL() << "a reference on pinion_fx at mu = 0 was made";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("monitor.signal = pinion_fx"), std::string::npos) << e.what();
  }
  // A reference on the bearings model does not fit a torsional gear, whose configuration leaves
  // the model's key out (its default), nor the reverse.
  s.monitor.signal = gd::MonitoredSignal::kPinionFy;
  const gd::Reference on_bearings = gd::build_reference(bearings_config(0.04), s);
  gd::ModelConfig torsional = bearings_config(0.04);
  torsional.gear.model = gd::GearModel::kTorsional;
  try {
    gd::check_reference(on_bearings, torsional, "ref.yaml");
    FAIL() << "a bearings reference was accepted for the torsional model";
  } catch (const gd::ReferenceError& e) {
    EXPECT_NE(std::string(e.what()).find("gear_pair.model = bearings"), std::string::npos) << e.what();
  }
  s.monitor.signal = gd::MonitoredSignal::kDelta;
  const gd::Reference on_torsional = gd::build_reference(torsional, s);
  EXPECT_THROW(gd::check_reference(on_torsional, bearings_config(0.04), "ref.yaml"), gd::ReferenceError);
  EXPECT_NO_THROW(gd::check_reference(on_bearings, bearings_config(0.04), "ref.yaml"));
  const gd::GearPair gear = gd::derive(paper_config().gear);
  EXPECT_THROW(gd::state_signal(gear, gd::MonitoredSignal::kWheelFy, 1e8, 0, 0, 1e-5, 0), std::invalid_argument);
}

// A bearing force's windows are the bearings model's outputs on the reference's grid: equal bit for
// bit to a lane stepped and cut by hand, and the mesh force's to the model's F_m to rounding (the
// state's formula with delta_m). The physics of the outputs: at mu = 0 nothing acts across the line
// of action (x identically 0), at 0.04 friction does; along it the bearings push the pinion
// against the mesh force and the wheel with it. (A TSA holds point values interpolated at 640
// angles per revolution, not time averages, so the force balance of the means is not checked on it.)
TEST(MonitorSignals, BearingForceWindowsAreTheModelsOutputs) {
  gd::MonitorSettings m;
  const double warmup = 0.1;
  std::map<gd::MonitoredSignal, Eigen::VectorXd> tsa;
  for (double mu : {0.0, 0.04}) {
    const gd::ModelConfig config = bearings_config(mu);
    for (const gd::MonitoredSignalSpec& s : gd::monitored_signals()) {
      m.signal = s.signal;
      const auto runs = gd::simulate_windows(config, m, 3, 1, warmup, 1);
      ASSERT_EQ(runs.size(), 1u);
      ASSERT_EQ(runs[0].size(), 1u);
      tsa[s.signal] = runs[0][0].tsa;
      if (!s.bearing_force) continue;
      const gd::RevolutionWindow by_hand = first_window_by_hand(config, m, 3, warmup, s.bearing_force);
      EXPECT_EQ(runs[0][0].tsa, by_hand.tsa) << s.name << " at mu " << mu;
      EXPECT_EQ(runs[0][0].mean_load, by_hand.mean_load) << s.name;
    }
    using S = gd::MonitoredSignal;
    // The mesh force signal of the bearings model is its output F_m (from delta_m and its rate).
    m.signal = S::kMeshForce;
    const Eigen::VectorXd model_force = first_window_by_hand(config, m, 3, warmup, &gd::BearingsOutputs::mesh_force).tsa;
    const double force = mean(tsa[S::kMeshForce]);
    EXPECT_LE((model_force - tsa[S::kMeshForce]).cwiseAbs().maxCoeff(), 1e-12 * force) << "mu " << mu;
    EXPECT_GT(force, 50.0);
    // The bearings hold the bodies against the mesh force: the pinion pushed along -y, the wheel +y.
    EXPECT_LT(tsa[S::kPinionFy].maxCoeff(), 0.0) << "mu " << mu;
    EXPECT_GT(tsa[S::kWheelFy].minCoeff(), 0.0) << "mu " << mu;
    if (mu == 0.0) {
      EXPECT_EQ(tsa[S::kPinionFx].cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ(tsa[S::kWheelFx].cwiseAbs().maxCoeff(), 0.0);
    } else {
      EXPECT_GT(tsa[S::kPinionFx].cwiseAbs().maxCoeff(), 0.01 * force);
    }
  }
}

// A reference on the pinion's bearing force along the line of action (the bearings model at
// 2000 m/s^2) holds its false-alarm rate on held-out streams: T^2 above its 5 % threshold in a
// fraction within 3 standard deviations of binomial sampling, inflated for the reference's own
// quantile, sqrt(a (1 - a) (1 / n_test + 1 / n_ref)) = 0.0136 at n = 512.
TEST(MonitorSignals, BearingForceReferenceHoldsItsFalseAlarmRate) {
  const gd::ModelConfig config = bearings_config(0.04);
  const int n = 512;
  auto s = settings(n);
  s.monitor.signal = gd::MonitoredSignal::kPinionFy;
  const gd::Reference ref = gd::build_reference(config, s);
  const auto runs = gd::simulate_windows(config, ref.settings.monitor, n, n, s.warmup, 1);
  gd::ConditionMonitor monitor(ref);
  int t2 = 0;
  for (const auto& run : runs) {
    monitor.reset();
    t2 += monitor.assess(run.at(0)).t2_alarm;
  }
  const double alpha = s.false_alarm, sd = std::sqrt(alpha * (1 - alpha) * (2.0 / n));
  std::printf("pinion_fy reference: T2 above its threshold in %d of %d held-out windows (nominal %.2f)\n", t2, n, alpha);
  EXPECT_NEAR(static_cast<double>(t2) / n, alpha, 3 * sd);
}
