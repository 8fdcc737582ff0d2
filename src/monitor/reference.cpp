#include "gear_dynamics/monitor/reference.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>

#include "gear_dynamics/maths/statistics.hpp"

namespace gear_dynamics {

namespace {

constexpr double kPi = 3.141592653589793;

template <class T>
void require(bool ok, const std::string& name, T value, const std::string& range) {
  if (ok) return;
  std::ostringstream e;
  e << "monitor." << name << " = " << value << " is out of range; allowed " << range;
  throw std::invalid_argument(e.str());
}

const char* gear_text(FaultyGear g) {
  return g == FaultyGear::kPinion ? "pinion" : g == FaultyGear::kWheel ? "wheel" : "none";
}

FaultyGear parse_gear(const std::string& text) {
  if (text == "pinion") return FaultyGear::kPinion;
  if (text == "wheel") return FaultyGear::kWheel;
  throw std::invalid_argument("monitor.gear = " + text + " is not allowed; allowed: pinion, wheel");
}

// The model configuration without its faults: a reference is of the healthy gear.
ModelConfig healthy_of(ModelConfig config) {
  config.gear.crack = RootCrack{};
  config.gear.spall = Spall{};
  return config;
}

}  // namespace

const std::vector<MonitoredSignalSpec>& monitored_signals() {
  using S = MonitoredSignal;
  using O = BearingsOutputs;
  static const std::vector<MonitoredSignalSpec> table = {
      {S::kDelta, "delta", "m", "the mesh deflection (delta_m in the bearings model)", nullptr, nullptr, false},
      {S::kMeshForce, "mesh_force", "N", "the mesh force F_m", nullptr, nullptr, false},
      {S::kPinionFx, "pinion_fx", "N", "the pinion's bearing force across the line of action (friction)",
       &O::pinion_fx, "pinion_bearing/wrench", true},
      {S::kPinionFy, "pinion_fy", "N", "the pinion's bearing force along the line of action", &O::pinion_fy,
       "pinion_bearing/wrench", false},
      {S::kWheelFx, "wheel_fx", "N", "the wheel's bearing force across the line of action (friction)",
       &O::wheel_fx, "wheel_bearing/wrench", true},
      {S::kWheelFy, "wheel_fy", "N", "the wheel's bearing force along the line of action", &O::wheel_fy,
       "wheel_bearing/wrench", false},
  };
  return table;
}

const MonitoredSignalSpec& signal_spec(MonitoredSignal signal) {
  const auto& table = monitored_signals();
  const auto i = static_cast<std::size_t>(signal);
  if (i >= table.size() || table[i].signal != signal) throw std::logic_error("monitored_signals(): out of the enum's order");
  return table[i];
}

const char* to_string(MonitoredSignal signal) { return signal_spec(signal).name; }

MonitoredSignal parse_monitored_signal(const std::string& text, const std::string& key) {
  std::string names;
  for (const MonitoredSignalSpec& s : monitored_signals()) {
    if (text == s.name) return s.signal;
    names += (names.empty() ? "" : ", ") + std::string(s.name);
  }
  throw std::invalid_argument(key + " = " + text + " is not allowed; allowed: " + names);
}

void require_signal(MonitoredSignal signal, GearModel model) {
  const MonitoredSignalSpec& s = signal_spec(signal);
  if (!s.bearing_force || model == GearModel::kBearings) return;
  std::string names;
  for (const MonitoredSignalSpec& o : monitored_signals())
    if (!o.bearing_force) names += (names.empty() ? "" : ", ") + std::string(o.name);
  throw std::invalid_argument(std::string("monitor.signal = ") + s.name +
                              " is an output of gear_pair.model = bearings; the torsional model gives: " + names);
}

const char* to_string(Health health) {
  return health == Health::kOk ? "OK" : health == Health::kWarn ? "WARN" : "ERROR";
}

void validate(const ReferenceSettings& s) {
  const auto& m = s.monitor;
  require(m.gear != FaultyGear::kNone, "gear", gear_text(m.gear), "pinion, wheel");
  require(m.revolutions_per_window >= 1 && m.revolutions_per_window <= 1000, "revolutions_per_window",
          m.revolutions_per_window, "[1, 1000]");
  require(m.decimation >= 1 && m.decimation <= 1000, "decimation", m.decimation, "[1, 1000]");
  require(s.realizations >= 2 && s.realizations <= 1000000, "realizations", s.realizations, "[2, 1000000]");
  require(s.windows >= 1 && s.windows <= 10000, "windows", s.windows, "[1, 10000]");
  require(s.warmup >= 0.0 && s.warmup <= 100.0, "warmup", s.warmup, "[0, 100] s");
  require(s.false_alarm > 0.0 && s.false_alarm < 0.5, "false_alarm", s.false_alarm, "(0, 0.5)");
  require(s.average_run_length >= 2.0 && s.average_run_length <= 1e7, "average_run_length", s.average_run_length,
          "[2, 1e7] windows");
  require(s.cusum_reference > 0.0 && s.cusum_reference <= 3.0, "cusum_reference", s.cusum_reference, "(0, 3]");
  require(s.first_realization < 1000000ULL, "first_realization", s.first_realization, "[0, 999999]");
  for (double l : s.load_means)
    require(std::isfinite(l) && std::abs(l) <= kMaxLoadMean, "load_means", l, "[-1e4, 1e4] m/s^2");
  // Enough windows for the (1 - alpha) quantile to be inside the sample.
  const double n = static_cast<double>(s.realizations) * s.windows;
  require(n * s.false_alarm >= 5.0, "realizations", s.realizations,
          "realizations x windows x false_alarm >= 5 (a quantile inside the sample)");
}

double revolution_angle(const GearPair& gear, FaultyGear which) {
  return which == FaultyGear::kWheel ? 2.0 * kPi * gear.in.gear_teeth / gear.in.pinion_teeth : 2.0 * kPi;
}
int monitored_teeth(const GearPair& gear, FaultyGear which) {
  return which == FaultyGear::kWheel ? gear.in.gear_teeth : gear.in.pinion_teeth;
}
double shaft_angle(const GearPair& gear, double t) { return gear.in.mesh_phase + gear.in.pinion_speed * t; }

IndicatorSettings indicator_settings(const GearPair& gear, const MonitorSettings& m) {
  IndicatorSettings s;
  s.teeth = monitored_teeth(gear, m.gear);
  s.samples_per_revolution = m.samples_per_revolution;
  s.shaft_orders = m.shaft_orders;
  s.sideband_orders = m.sideband_orders;
  s.envelope_band = m.envelope_band;
  validate(s);
  return s;
}

double state_signal(const GearPair& gear, MonitoredSignal signal, double stiffness, double error, double error_rate,
                    double delta, double delta_dot) {
  if (signal == MonitoredSignal::kDelta) return delta;
  if (signal == MonitoredSignal::kMeshForce) return mesh_force(gear, stiffness, delta, delta_dot, error, error_rate);
  throw std::invalid_argument(std::string("state_signal: ") + to_string(signal) +
                              " is not a state's signal (the bearings outputs or its wrench hold it)");
}

std::vector<std::vector<RevolutionWindow>> simulate_windows(const ModelConfig& config, const MonitorSettings& m,
                                                            std::uint64_t first, int count, double warmup,
                                                            int windows) {
  require_signal(m.signal, config.gear.model);
  const GearPair gear = derive(config.gear);
  const MonitoredSignalSpec& spec = signal_spec(m.signal);
  const double revolution = revolution_angle(gear, m.gear);
  const double h = config.run.time_step, omega = gear.in.pinion_speed;
  // The last window ends (revolutions counted from the first aligned start after the warm-up).
  const double start = std::ceil(shaft_angle(gear, warmup) / revolution) * revolution;
  const double end = start + static_cast<double>(windows) * m.revolutions_per_window * revolution;
  const std::int64_t steps =
      static_cast<std::int64_t>(std::ceil((end - gear.in.mesh_phase) / omega / h)) + 2 * m.decimation;
  const std::int64_t first_recorded = static_cast<std::int64_t>(std::floor(warmup / h));

  std::vector<std::vector<RevolutionWindow>> out(count);
  constexpr int kBlock = 256;  // lanes per ensemble: its normals stay in cache
  for (int b0 = 0; b0 < count; b0 += kBlock) {
    const int lanes = std::min(kBlock, count - b0);
    std::vector<LaneSpec> specs;
    for (int i = 0; i < lanes; ++i)
      specs.push_back(stochastic_lane(config, config.friction_coefficient, first + static_cast<std::uint64_t>(b0 + i)));
    Ensemble ensemble(gear, h, config.initial, specs, config.seed);
    std::vector<RevolutionWindows> cut(lanes, RevolutionWindows(revolution, m.revolutions_per_window,
                                                                m.samples_per_revolution));
    for (std::int64_t n = 0; n < steps; ++n) {
      ensemble.step();
      const std::int64_t k = ensemble.step_index();
      if (k < first_recorded || k % m.decimation != 0) continue;
      const double t = ensemble.time(), angle = shaft_angle(gear, t);
      const model_step::MeshPoint mesh = output_mesh_point(ensemble.mesh(), t);  // the block's, for all lanes
      for (int i = 0; i < lanes; ++i) {
        auto& mine = out[b0 + i];
        if (static_cast<int>(mine.size()) >= windows) continue;
        const double value =
            spec.bearing_force
                ? bearings_outputs(ensemble, mesh, i).*spec.bearing_force
                : state_signal(gear, m.signal, mesh.stiffness, mesh.error, mesh.error_rate, ensemble.padded_delta()(i),
                               ensemble.padded_velocity()(i));
        if (auto w = cut[i].add(angle, value, ensemble.load()(i))) mine.push_back(std::move(*w));
      }
    }
  }
  return out;
}

double siegmund_arl(double k, double h, double mu) {
  const double d = mu - k, b = h + 1.166;
  if (std::abs(d) < 1e-12) return b * b;
  return (std::exp(-2.0 * d * b) + 2.0 * d * b - 1.0) / (2.0 * d * d);
}

double cusum_threshold_for(double k, double arl) {
  double lo = 0.0, hi = 60.0;  // Siegmund's ARL grows with h: bisection
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (siegmund_arl(k, mid) < arl ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double hotelling_t2(const ReferenceBand& band, const std::vector<double>& x) {
  const Eigen::Index p = static_cast<Eigen::Index>(band.mean.size());
  Eigen::VectorXd z(p);
  for (Eigen::Index i = 0; i < p; ++i) {
    if (!std::isfinite(x[i])) return std::numeric_limits<double>::infinity();
    z(i) = band.sd[i] > 0.0 ? (x[i] - band.mean[i]) / band.sd[i] : 0.0;
  }
  return z.dot(band.inverse_correlation * z);
}

double t2_score(const ReferenceBand& band, double t2) {
  // Mid-rank among the n reference values, (below + equal / 2 + 1/2) / (n + 1): in (0, 1), uniform
  // on the ranks for a healthy window exchangeable with the reference's.
  const auto lo = std::lower_bound(band.t2.begin(), band.t2.end(), t2);
  const auto hi = std::upper_bound(band.t2.begin(), band.t2.end(), t2);
  const double n = static_cast<double>(band.t2.size());
  const double below = static_cast<double>(lo - band.t2.begin());
  const double equal = static_cast<double>(hi - lo);
  const double p = (below + 0.5 * equal + 0.5) / (n + 1.0);
  return boost::math::quantile(boost::math::normal(), p);
}

bool Reference::covers(double load) const {
  return !bands.empty() && load >= bands.front().load_low && load <= bands.back().load_high;
}

std::size_t Reference::band_of(double load) const {
  for (std::size_t i = 0; i < bands.size(); ++i)
    if (load < bands[i].load_high) return i;
  return bands.empty() ? 0 : bands.size() - 1;
}

Reference build_reference(const ModelConfig& model, const ReferenceSettings& settings) {
  validate(settings);
  const ModelConfig healthy = healthy_of(model);
  const GearPair gear = derive(healthy.gear);
  const IndicatorSettings ind = indicator_settings(gear, settings.monitor);

  Reference ref;
  ref.package_version = GEAR_DYNAMICS_VERSION;
  ref.numbers = kNumbersGeneration;
  ref.config = to_yaml(healthy);
  ref.settings = settings;
  ref.indicators = indicator_names();
  ref.cusum_threshold = cusum_threshold_for(settings.cusum_reference, settings.average_run_length);

  std::vector<double> loads = settings.load_means;
  if (loads.empty()) loads.push_back(healthy.load.initial_mean);
  std::sort(loads.begin(), loads.end());
  const std::size_t p = ref.indicators.size();
  const double alpha = settings.false_alarm;
  for (std::size_t b = 0; b < loads.size(); ++b) {
    ModelConfig at = healthy;
    at.load.initial_mean = loads[b];
    const auto runs = simulate_windows(at, settings.monitor, settings.first_realization, settings.realizations,
                                       settings.warmup, settings.windows);
    ReferenceBand band;
    band.load = loads[b];
    // Inner edges halfway between the nominal loads; the outer ones where the reference's windows
    // end: beyond them it has no healthy window to compare with (the live load wanders).
    double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
    for (const auto& run : runs)
      for (const auto& w : run) {
        lowest = std::min(lowest, w.mean_load);
        highest = std::max(highest, w.mean_load);
      }
    band.load_low = b == 0 ? lowest : 0.5 * (loads[b - 1] + loads[b]);
    band.load_high = b + 1 == loads.size() ? highest : 0.5 * (loads[b] + loads[b + 1]);

    // NA4*'s baseline: the mean residual variance of the healthy windows.
    double residual = 0.0;
    std::size_t count = 0;
    for (const auto& run : runs)
      for (const auto& w : run) {
        residual += variance(decompose(w.tsa, ind).residual);
        ++count;
      }
    band.windows = count;
    band.baseline_residual_variance = residual / static_cast<double>(count);

    std::vector<std::vector<double>> rows;
    for (const auto& run : runs) {
      IndicatorTracker tracker(ind, band.baseline_residual_variance);
      for (const auto& w : run) {
        rows.push_back(tracker.window(w.tsa));
        for (std::size_t i = 0; i < p; ++i)
          if (!std::isfinite(rows.back()[i]))
            throw std::runtime_error("build_reference: indicator " + ref.indicators[i] + " of monitor.signal = " +
                                     to_string(settings.monitor.signal) +
                                     " is not finite on a healthy window (a constant signal: across the line of "
                                     "action, a bearing force is 0 at gear_pair.friction_coefficient = 0)");
      }
    }
    const double n = static_cast<double>(rows.size());
    band.mean.assign(p, 0.0);
    band.sd.assign(p, 0.0);
    band.threshold.assign(p, 0.0);
    for (std::size_t i = 0; i < p; ++i) {
      std::vector<double> col;
      for (const auto& r : rows) col.push_back(r[i]);
      double m = 0.0;
      for (double v : col) m += v;
      m /= n;
      double ss = 0.0;
      for (double v : col) ss += (v - m) * (v - m);
      band.mean[i] = m;
      band.sd[i] = std::sqrt(ss / (n - 1.0));
      std::sort(col.begin(), col.end());
      band.threshold[i] = quantile_sorted(col, 1.0 - alpha);
    }
    Eigen::MatrixXd z(rows.size(), p);
    for (std::size_t r = 0; r < rows.size(); ++r)
      for (std::size_t i = 0; i < p; ++i)
        z(r, i) = band.sd[i] > 0.0 ? (rows[r][i] - band.mean[i]) / band.sd[i] : 0.0;
    const Eigen::MatrixXd corr = (z.transpose() * z) / (n - 1.0);
    // Pseudo-inverse: indicators that move together (FM4 and M6A, say) leave directions of ~0
    // variance, which a plain inverse would weigh without bound.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(corr);
    const Eigen::VectorXd lambda = eig.eigenvalues();
    const double cut = 1e-9 * lambda.maxCoeff();
    Eigen::VectorXd inv = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p));
    for (Eigen::Index i = 0; i < lambda.size(); ++i)
      if (lambda(i) > cut) {
        inv(i) = 1.0 / lambda(i);
        ++band.rank;
      }
    band.inverse_correlation = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
    for (const auto& r : rows) band.t2.push_back(hotelling_t2(band, r));
    std::sort(band.t2.begin(), band.t2.end());
    band.t2_threshold = quantile_sorted(band.t2, 1.0 - alpha);
    const double q = band.rank;
    if (n > q + 1) {
      const boost::math::fisher_f f(q, n - q);
      band.t2_threshold_f = q * (n + 1.0) * (n - 1.0) / (n * (n - q)) * boost::math::quantile(f, 1.0 - alpha);
    } else {
      band.t2_threshold_f = std::numeric_limits<double>::quiet_NaN();
    }
    ref.bands.push_back(std::move(band));
  }
  return ref;
}

// ---- the file ----

namespace {

void emit_vector(YAML::Emitter& out, const std::vector<double>& v) {
  out << YAML::Flow << YAML::BeginSeq;
  for (double x : v) out << x;
  out << YAML::EndSeq;
}

}  // namespace

std::string reference_text(const Reference& ref) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  const auto& s = ref.settings;
  const auto& m = s.monitor;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kReferenceFormat;
  out << YAML::Key << "package_version" << YAML::Value << ref.package_version;
  out << YAML::Key << "numbers" << YAML::Value << ref.numbers;
  out << YAML::Key << "monitor" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "signal" << YAML::Value << to_string(m.signal);
  out << YAML::Key << "gear" << YAML::Value << gear_text(m.gear);
  out << YAML::Key << "revolutions_per_window" << YAML::Value << m.revolutions_per_window;
  out << YAML::Key << "samples_per_revolution" << YAML::Value << m.samples_per_revolution;
  out << YAML::Key << "shaft_orders" << YAML::Value << m.shaft_orders;
  out << YAML::Key << "sideband_orders" << YAML::Value << m.sideband_orders;
  out << YAML::Key << "envelope_band" << YAML::Value << m.envelope_band;
  out << YAML::Key << "decimation" << YAML::Value << m.decimation;
  out << YAML::Key << "first_realization" << YAML::Value << s.first_realization;
  out << YAML::Key << "realizations" << YAML::Value << s.realizations;
  out << YAML::Key << "windows" << YAML::Value << s.windows;
  out << YAML::Key << "warmup" << YAML::Value << s.warmup;
  out << YAML::Key << "false_alarm" << YAML::Value << s.false_alarm;
  out << YAML::Key << "average_run_length" << YAML::Value << s.average_run_length;
  out << YAML::Key << "cusum_reference" << YAML::Value << s.cusum_reference;
  out << YAML::Key << "load_means" << YAML::Value;
  emit_vector(out, s.load_means);
  out << YAML::EndMap;
  out << YAML::Key << "config" << YAML::Value << ref.config;
  out << YAML::Key << "indicators" << YAML::Value << YAML::Flow << ref.indicators;
  out << YAML::Key << "cusum_threshold" << YAML::Value << ref.cusum_threshold;
  out << YAML::Key << "bands" << YAML::Value << YAML::BeginSeq;
  for (const auto& b : ref.bands) {
    out << YAML::BeginMap;
    out << YAML::Key << "load" << YAML::Value << b.load;
    out << YAML::Key << "load_low" << YAML::Value << b.load_low;
    out << YAML::Key << "load_high" << YAML::Value << b.load_high;
    out << YAML::Key << "windows" << YAML::Value << b.windows;
    out << YAML::Key << "baseline_residual_variance" << YAML::Value << b.baseline_residual_variance;
    out << YAML::Key << "mean" << YAML::Value;
    emit_vector(out, b.mean);
    out << YAML::Key << "sd" << YAML::Value;
    emit_vector(out, b.sd);
    out << YAML::Key << "threshold" << YAML::Value;
    emit_vector(out, b.threshold);
    out << YAML::Key << "rank" << YAML::Value << b.rank;
    out << YAML::Key << "inverse_correlation" << YAML::Value << YAML::BeginSeq;
    for (Eigen::Index r = 0; r < b.inverse_correlation.rows(); ++r) {
      std::vector<double> row(b.inverse_correlation.cols());
      for (Eigen::Index c = 0; c < b.inverse_correlation.cols(); ++c) row[c] = b.inverse_correlation(r, c);
      emit_vector(out, row);
    }
    out << YAML::EndSeq;
    out << YAML::Key << "t2_threshold" << YAML::Value << b.t2_threshold;
    out << YAML::Key << "t2_threshold_f" << YAML::Value << b.t2_threshold_f;
    out << YAML::Key << "t2" << YAML::Value;
    emit_vector(out, b.t2);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void write_reference(const std::string& path, const Reference& ref) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    f << reference_text(ref);
    if (!f) throw std::runtime_error("cannot write the reference " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

namespace {

template <class T>
T field(const YAML::Node& node, const std::string& key, const std::string& where, const std::string& path) {
  const YAML::Node v = node[key];
  if (!v) throw ReferenceError("reference " + path + ": " + where + key + " is missing");
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    throw ReferenceError("reference " + path + ": " + where + key + " = " + YAML::Dump(v) + " is not a valid value");
  }
}

}  // namespace

Reference read_reference(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw ReferenceError("reference " + path + " cannot be read: " + e.what());
  }
  if (!root.IsMap()) throw ReferenceError("reference " + path + " is not a YAML map");
  const auto format = field<std::string>(root, "format", "", path);
  if (format != kReferenceFormat)
    throw ReferenceError("reference " + path + " has format " + format + "; this build reads " + kReferenceFormat);
  Reference ref;
  ref.package_version = field<std::string>(root, "package_version", "", path);
  ref.numbers = field<int>(root, "numbers", "", path);
  if (ref.numbers != kNumbersGeneration)
    throw ReferenceError("reference " + path + " was made by numbers generation " + std::to_string(ref.numbers) +
                         ", this build's is " + std::to_string(kNumbersGeneration) + ": make it again");
  const YAML::Node m = root["monitor"];
  if (!m || !m.IsMap()) throw ReferenceError("reference " + path + ": monitor is missing");
  auto& s = ref.settings;
  try {
    s.monitor.signal = parse_monitored_signal(field<std::string>(m, "signal", "monitor.", path));
    s.monitor.gear = parse_gear(field<std::string>(m, "gear", "monitor.", path));
  } catch (const std::invalid_argument& e) {
    throw ReferenceError("reference " + path + ": " + e.what());
  }
  s.monitor.revolutions_per_window = field<int>(m, "revolutions_per_window", "monitor.", path);
  s.monitor.samples_per_revolution = field<int>(m, "samples_per_revolution", "monitor.", path);
  s.monitor.shaft_orders = field<int>(m, "shaft_orders", "monitor.", path);
  s.monitor.sideband_orders = field<int>(m, "sideband_orders", "monitor.", path);
  s.monitor.envelope_band = field<int>(m, "envelope_band", "monitor.", path);
  s.monitor.decimation = field<int>(m, "decimation", "monitor.", path);
  s.first_realization = field<std::uint64_t>(m, "first_realization", "monitor.", path);
  s.realizations = field<int>(m, "realizations", "monitor.", path);
  s.windows = field<int>(m, "windows", "monitor.", path);
  s.warmup = field<double>(m, "warmup", "monitor.", path);
  s.false_alarm = field<double>(m, "false_alarm", "monitor.", path);
  s.average_run_length = field<double>(m, "average_run_length", "monitor.", path);
  s.cusum_reference = field<double>(m, "cusum_reference", "monitor.", path);
  s.load_means = field<std::vector<double>>(m, "load_means", "monitor.", path);
  try {
    validate(s);
  } catch (const std::invalid_argument& e) {
    throw ReferenceError("reference " + path + ": " + e.what());
  }
  ref.config = root["config"];
  if (!ref.config || !ref.config["gear_pair"]) throw ReferenceError("reference " + path + ": config.gear_pair is missing");
  ref.indicators = field<std::vector<std::string>>(root, "indicators", "", path);
  if (ref.indicators != indicator_names()) {
    std::string theirs, ours;
    for (const auto& n : ref.indicators) theirs += (theirs.empty() ? "" : ", ") + n;
    for (const auto& n : indicator_names()) ours += (ours.empty() ? "" : ", ") + n;
    throw ReferenceError("reference " + path + " lists the indicators [" + theirs + "], this build computes [" + ours +
                         "]: make it again");
  }
  ref.cusum_threshold = field<double>(root, "cusum_threshold", "", path);
  const YAML::Node bands = root["bands"];
  if (!bands || !bands.IsSequence() || bands.size() == 0)
    throw ReferenceError("reference " + path + ": bands is missing or empty");
  const std::size_t p = ref.indicators.size();
  for (std::size_t i = 0; i < bands.size(); ++i) {
    const std::string where = "bands[" + std::to_string(i) + "].";
    const YAML::Node b = bands[i];
    ReferenceBand band;
    band.load = field<double>(b, "load", where, path);
    band.load_low = field<double>(b, "load_low", where, path);
    band.load_high = field<double>(b, "load_high", where, path);
    band.windows = field<std::size_t>(b, "windows", where, path);
    band.baseline_residual_variance = field<double>(b, "baseline_residual_variance", where, path);
    band.mean = field<std::vector<double>>(b, "mean", where, path);
    band.sd = field<std::vector<double>>(b, "sd", where, path);
    band.threshold = field<std::vector<double>>(b, "threshold", where, path);
    band.rank = field<int>(b, "rank", where, path);
    const auto rows = field<std::vector<std::vector<double>>>(b, "inverse_correlation", where, path);
    band.t2_threshold = field<double>(b, "t2_threshold", where, path);
    band.t2_threshold_f = field<double>(b, "t2_threshold_f", where, path);
    band.t2 = field<std::vector<double>>(b, "t2", where, path);
    bool ok = band.mean.size() == p && band.sd.size() == p && band.threshold.size() == p && rows.size() == p &&
              !band.t2.empty() && std::is_sorted(band.t2.begin(), band.t2.end());
    for (const auto& r : rows) ok = ok && r.size() == p;
    if (!ok)
      throw ReferenceError("reference " + path + ": " + where + " does not hold " + std::to_string(p) +
                           " indicators (mean, sd, threshold, a square inverse_correlation) and a sorted t2");
    band.inverse_correlation.resize(p, p);
    for (std::size_t r = 0; r < p; ++r)
      for (std::size_t c = 0; c < p; ++c) band.inverse_correlation(r, c) = rows[r][c];
    ref.bands.push_back(std::move(band));
  }
  return ref;
}

void check_reference(const Reference& ref, const ModelConfig& monitored, const std::string& path) {
  const YAML::Node mine = to_yaml(monitored)["gear_pair"];
  const YAML::Node theirs = ref.config["gear_pair"];
  // Keys of either side: to_yaml leaves out some at their defaults (the model's, when torsional).
  std::set<std::string> keys;
  for (const YAML::Node& side : {mine, theirs})
    for (const auto& kv : side) keys.insert(kv.first.as<std::string>());
  for (const std::string& key : keys) {
    if (key.rfind("crack_", 0) == 0 || key.rfind("spall_", 0) == 0) continue;  // the faults monitored
    const auto text = [&](const YAML::Node& side) {
      return side[key] ? YAML::Dump(side[key]) : std::string("(absent: its default)");
    };
    const std::string a = text(theirs), b = text(mine);
    if (a != b)
      throw ReferenceError("reference " + path + " was made for another gear: gear_pair." + key + " = " + a +
                           " there, the monitored gear has " + b + " (make a reference for this gear)");
  }
}

ConditionMonitor::ConditionMonitor(Reference reference)
    : reference_(std::move(reference)),
      revolution_(0.0),
      tracker_(indicator_settings(derive(parse_config(reference_.config).gear), reference_.settings.monitor)) {
  revolution_ = gear_dynamics::revolution_angle(derive(parse_config(reference_.config).gear),
                                                reference_.settings.monitor.gear);
}

void ConditionMonitor::reset() {
  tracker_.reset();
  cusum_ = 0.0;
}

Assessment ConditionMonitor::assess(const RevolutionWindow& window) {
  Assessment a;
  a.load = window.mean_load;
  a.band = reference_.band_of(window.mean_load);
  const ReferenceBand& band = reference_.bands[a.band];
  tracker_.set_baseline(band.baseline_residual_variance);
  a.indicators = tracker_.window(window.tsa);
  a.exceeded.resize(a.indicators.size());
  for (std::size_t i = 0; i < a.indicators.size(); ++i) a.exceeded[i] = a.indicators[i] > band.threshold[i];
  a.t2 = hotelling_t2(band, a.indicators);
  a.score = t2_score(band, a.t2);
  a.in_reference = reference_.covers(window.mean_load);
  if (!a.in_reference) {
    // Not judged: the CUSUM holds, and the WARN says the monitor is blind at this load.
    a.cusum = cusum_;
    a.health = Health::kWarn;
    return a;
  }
  cusum_ = std::max(0.0, cusum_ + a.score - reference_.settings.cusum_reference);
  a.cusum = cusum_;
  a.t2_alarm = a.t2 > band.t2_threshold;
  a.cusum_alarm = cusum_ > reference_.cusum_threshold;
  a.health = a.cusum_alarm ? Health::kError : a.t2_alarm ? Health::kWarn : Health::kOk;
  return a;
}

}  // namespace gear_dynamics
