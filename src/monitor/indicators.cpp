#include "gear_dynamics/monitor/indicators.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

namespace gear_dynamics {

namespace {

void require(bool ok, const std::string& name, double value, const std::string& range) {
  if (ok) return;
  std::ostringstream e;
  e << "monitor." << name << " = " << value << " is out of range; allowed " << range;
  throw std::invalid_argument(e.str());
}

double mean(const Eigen::VectorXd& x) { return x.size() ? x.mean() : 0.0; }

// (1/N) sum (x - mean)^k by repeated products: exact powers, and no vectorised pow (GCC 12's
// AVX-512 headers trip -Wuninitialized there, bug 105593).
double central_moment(const Eigen::VectorXd& x, int k) {
  const double m = mean(x);
  double sum = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double d = x(i) - m;
    double p = 1.0;
    for (int j = 0; j < k; ++j) p *= d;
    sum += p;
  }
  return x.size() ? sum / static_cast<double>(x.size()) : 0.0;
}

double rms_ac(const Eigen::VectorXd& x) { return std::sqrt(variance(x)); }

// --- the indicators: one function each, declared in indicator_table() below ---

// RMS, kurtosis and crest factor of the TSA about its mean: a deflection's static part follows
// the load, not the tooth.
double rms(const GearSignals& s, const IndicatorContext&) { return rms_ac(s.tsa); }
double kurtosis(const GearSignals& s, const IndicatorContext&) { return normalized_moment(s.tsa, 4); }
double crest_factor(const GearSignals& s, const IndicatorContext&) {
  return (s.tsa.array() - mean(s.tsa)).abs().maxCoeff() / rms_ac(s.tsa);
}
// Peak-to-peak of the TSA over the sum of the mesh harmonics' amplitudes (Stewart's FM0).
double fm0(const GearSignals& s, const IndicatorContext&) {
  double sum = 0.0;
  const int half = static_cast<int>(s.amplitude.size()) - 1;
  for (int k = s.mesh_order; k <= half; k += s.mesh_order) sum += s.amplitude(k);
  return (s.tsa.maxCoeff() - s.tsa.minCoeff()) / sum;
}
double fm4(const GearSignals& s, const IndicatorContext&) { return normalized_moment(s.difference, 4); }
double m6a(const GearSignals& s, const IndicatorContext&) { return normalized_moment(s.difference, 6); }
double m8a(const GearSignals& s, const IndicatorContext&) { return normalized_moment(s.difference, 8); }
// Fourth moment of the residual over the square of the run's mean residual variance (Zakrajsek).
double na4(const GearSignals& s, const IndicatorContext& c) {
  return central_moment(s.residual, 4) / (c.residual_variance_trend * c.residual_variance_trend);
}
// The same over a healthy gear's residual variance (Decker's NA4*); NaN without a baseline.
double na4_star(const GearSignals& s, const IndicatorContext& c) {
  return central_moment(s.residual, 4) / (c.baseline_residual_variance * c.baseline_residual_variance);
}
// NA4's recipe on the envelope of the band around the mesh order.
double nb4(const GearSignals& s, const IndicatorContext& c) {
  return central_moment(s.envelope, 4) / (c.envelope_variance_trend * c.envelope_variance_trend);
}
// RMS of the difference signal over that of the regular meshing components (Swansson).
double energy_ratio(const GearSignals& s, const IndicatorContext&) { return rms_ac(s.difference) / rms_ac(s.regular); }
// (SB-1 + SB+1) / sd of the TSA: Lebold's sideband level factor.
double sideband_level(const GearSignals& s, const IndicatorContext&) {
  return (s.amplitude(s.mesh_order - 1) + s.amplitude(s.mesh_order + 1)) / rms_ac(s.tsa);
}
// (SB-1 + SB+1) / 2: the mean first-order sideband of the mesh order.
double sideband_index(const GearSignals& s, const IndicatorContext&) {
  return 0.5 * (s.amplitude(s.mesh_order - 1) + s.amplitude(s.mesh_order + 1));
}

}  // namespace

const std::vector<IndicatorSpec>& indicator_table() {
  static const std::vector<IndicatorSpec> table{
      {"rms", "signal", "RMS of the TSA about its mean", rms},
      {"kurtosis", "-", "kurtosis of the TSA (3: Gaussian, 1.5: a sine)", kurtosis},
      {"crest_factor", "-", "largest |TSA - mean| over its RMS", crest_factor},
      {"fm0", "-", "peak-to-peak of the TSA over the sum of the mesh harmonics' amplitudes", fm0},
      {"fm4", "-", "kurtosis of the difference signal", fm4},
      {"m6a", "-", "sixth normalised moment of the difference signal", m6a},
      {"m8a", "-", "eighth normalised moment of the difference signal", m8a},
      {"na4", "-", "fourth moment of the residual over the run's mean residual variance squared", na4},
      {"na4_star", "-", "fourth moment of the residual over the healthy reference's variance squared", na4_star},
      {"nb4", "-", "NA4's recipe on the envelope of the band around the mesh order", nb4},
      {"energy_ratio", "-", "RMS of the difference signal over that of the regular signal", energy_ratio},
      {"sideband_level", "-", "first-order sidebands of the mesh order, summed, over the TSA's sd", sideband_level},
      {"sideband_index", "signal", "mean amplitude of the mesh order's two first-order sidebands", sideband_index},
  };
  return table;
}

std::vector<std::string> indicator_names() {
  std::vector<std::string> names;
  for (const auto& spec : indicator_table()) names.emplace_back(spec.name);
  return names;
}

std::size_t indicator_index(const std::string& name) {
  const auto& table = indicator_table();
  for (std::size_t i = 0; i < table.size(); ++i)
    if (name == table[i].name) return i;
  std::string all;
  for (const auto& spec : table) all += std::string(all.empty() ? "" : ", ") + spec.name;
  throw std::invalid_argument("unknown condition indicator '" + name + "'; known: " + all);
}

void validate(const IndicatorSettings& s) {
  require(s.teeth >= 3 && s.teeth <= 10000, "teeth", s.teeth, "[3, 10000]");
  require(s.shaft_orders >= 0 && s.shaft_orders < s.teeth - s.sideband_orders, "shaft_orders", s.shaft_orders,
          "[0, teeth - sideband_orders - 1] (below the first sideband)");
  require(s.sideband_orders >= 1 && s.sideband_orders < s.teeth / 2, "sideband_orders", s.sideband_orders,
          "[1, teeth / 2 - 1]");
  require(s.envelope_band >= 0 && s.envelope_band < s.teeth, "envelope_band", s.envelope_band,
          "[0, teeth - 1] (0: teeth / 2)");
  const int top = s.teeth + std::max(s.sideband_orders, s.band());
  require(s.samples_per_revolution > 2 * top && s.samples_per_revolution <= (1 << 20), "samples_per_revolution",
          s.samples_per_revolution,
          "[" + std::to_string(2 * top + 1) + ", 1048576] (the mesh order, its sidebands and NB4's band below Nyquist)");
}

double variance(const Eigen::VectorXd& x) { return central_moment(x, 2); }

double normalized_moment(const Eigen::VectorXd& x, int k) {
  const double m2 = central_moment(x, 2);
  return central_moment(x, k) / std::pow(m2, 0.5 * k);
}

GearSignals decompose(const Eigen::VectorXd& tsa, const IndicatorSettings& settings) {
  const int n = static_cast<int>(tsa.size());
  if (n != settings.samples_per_revolution) {
    std::ostringstream e;
    e << "decompose: the TSA has " << n << " points, monitor.samples_per_revolution = "
      << settings.samples_per_revolution;
    throw std::invalid_argument(e.str());
  }
  const int z = settings.teeth, half = n / 2;
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> x(n), spectrum;
  for (int i = 0; i < n; ++i) x[i] = tsa(i);
  fft.fwd(spectrum, x);

  GearSignals s;
  s.mesh_order = z;
  s.tsa = tsa;
  s.amplitude.resize(half + 1);
  for (int k = 0; k <= half; ++k) {
    const bool edge = k == 0 || (n % 2 == 0 && k == half);
    s.amplitude(k) = (edge ? 1.0 : 2.0) * std::abs(spectrum[k]) / n;
  }
  // Which orders each signal keeps (orders k and n - k together).
  std::vector<char> mesh(half + 1, 0), shaft(half + 1, 0), side(half + 1, 0);
  for (int k = z; k <= half; k += z) {
    mesh[k] = 1;
    for (int j = 1; j <= settings.sideband_orders; ++j) {
      if (k - j > 0) side[k - j] = 1;
      if (k + j <= half) side[k + j] = 1;
    }
  }
  for (int k = 1; k <= std::min(settings.shaft_orders, half); ++k) shaft[k] = 1;

  const auto synthesize = [&](auto keep) {
    std::vector<std::complex<double>> y(n, 0.0), out;
    for (int k = 0; k < n; ++k) {
      const int order = k <= half ? k : n - k;
      if (keep(order)) y[k] = spectrum[k];
    }
    fft.inv(out, y);
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v(i) = out[i].real();
    return v;
  };
  s.regular = synthesize([&](int k) { return mesh[k] != 0; });
  s.residual = synthesize([&](int k) { return k != 0 && !mesh[k] && !shaft[k]; });
  s.difference = synthesize([&](int k) { return k != 0 && !mesh[k] && !shaft[k] && !side[k]; });

  // Analytic signal of the band: the positive orders doubled, the negative ones dropped.
  std::vector<std::complex<double>> band(n, 0.0), analytic;
  for (int k = std::max(1, z - settings.band()); k <= std::min(half - 1, z + settings.band()); ++k)
    band[k] = 2.0 * spectrum[k];
  fft.inv(analytic, band);
  s.envelope.resize(n);
  for (int i = 0; i < n; ++i) s.envelope(i) = std::abs(analytic[i]);
  return s;
}

IndicatorTracker::IndicatorTracker(const IndicatorSettings& settings, double baseline_residual_variance)
    : settings_(settings), baseline_(baseline_residual_variance) {
  validate(settings_);
}

void IndicatorTracker::reset() {
  residual_sum_ = envelope_sum_ = 0.0;
  windows_ = 0;
}

std::vector<double> IndicatorTracker::window(const Eigen::VectorXd& tsa) {
  GearSignals signals;
  return window(tsa, signals);
}

std::vector<double> IndicatorTracker::window(const Eigen::VectorXd& tsa, GearSignals& signals) {
  signals = decompose(tsa, settings_);
  residual_sum_ += variance(signals.residual);
  envelope_sum_ += variance(signals.envelope);
  ++windows_;
  IndicatorContext context;
  context.residual_variance_trend = residual_sum_ / windows_;
  context.envelope_variance_trend = envelope_sum_ / windows_;
  context.baseline_residual_variance = baseline_;
  std::vector<double> values;
  values.reserve(indicator_table().size());
  for (const auto& spec : indicator_table()) values.push_back(spec.compute(signals, context));
  return values;
}

RevolutionWindows::RevolutionWindows(double revolution_angle, int revolutions, int samples_per_revolution)
    : revolution_(revolution_angle),
      step_(revolution_angle / samples_per_revolution),
      revolutions_(revolutions),
      samples_(samples_per_revolution) {
  require(revolution_angle > 0.0 && std::isfinite(revolution_angle), "revolution_angle", revolution_angle, "(0, inf) rad");
  require(revolutions >= 1 && revolutions <= 100000, "revolutions_per_window", revolutions, "[1, 100000]");
  require(samples_per_revolution >= 8 && samples_per_revolution <= (1 << 20), "samples_per_revolution",
          samples_per_revolution, "[8, 1048576]");
  sum_ = Eigen::VectorXd::Zero(samples_);
}

void RevolutionWindows::restart() {
  have_previous_ = false;
  next_ = 0;
  sum_.setZero();
  load_sum_ = 0.0;
  load_count_ = 0;
  index_ = 0;
}

std::optional<RevolutionWindow> RevolutionWindows::add(double angle, double value, double load) {
  if (!std::isfinite(angle) || !std::isfinite(value)) {
    if (have_previous_) ++restarts_;
    restart();
    return std::nullopt;
  }
  if (have_previous_ && (!(angle > angle0_) || angle - angle0_ > revolution_)) {
    ++restarts_;
    restart();
  }
  if (!have_previous_) {
    have_previous_ = true;
    angle0_ = angle;
    value0_ = value;
    window_start_ = std::ceil(angle / revolution_) * revolution_;
    if (angle == window_start_) {  // a sample on the grid point itself
      sum_(0) += value;
      next_ = 1;
      load_sum_ += load;
      load_count_ = 1;
    }
    return std::nullopt;
  }
  const std::int64_t total = static_cast<std::int64_t>(revolutions_) * samples_;
  const double window_end = window_start_ + revolutions_ * revolution_;
  if (angle > window_start_ && angle < window_end) {
    load_sum_ += load;
    ++load_count_;
  }
  std::optional<RevolutionWindow> done;
  for (;;) {
    const double grid = window_start_ + static_cast<double>(next_) * step_;
    if (grid > angle) break;
    const double w = (grid - angle0_) / (angle - angle0_);
    sum_(next_ % samples_) += value0_ + w * (value - value0_);
    if (++next_ == total) {
      RevolutionWindow out;
      out.tsa = sum_ / revolutions_;
      out.mean_load = load_count_ ? load_sum_ / static_cast<double>(load_count_) : load;
      out.start_angle = window_start_;
      out.index = index_++;
      done = std::move(out);
      window_start_ += revolutions_ * revolution_;
      next_ = 0;
      sum_.setZero();
      load_sum_ = 0.0;
      load_count_ = 0;
      if (angle > window_start_) {
        load_sum_ += load;
        ++load_count_;
      }
    }
  }
  angle0_ = angle;
  value0_ = value;
  return done;
}

Eigen::VectorXd time_synchronous_average(const std::vector<double>& value, const std::vector<double>& angle,
                                         double revolution_angle, int samples_per_revolution, int* revolutions) {
  if (value.size() != angle.size())
    throw std::invalid_argument("time_synchronous_average: " + std::to_string(value.size()) + " values but " +
                                std::to_string(angle.size()) + " angles");
  RevolutionWindows windows(revolution_angle, 1, samples_per_revolution);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(samples_per_revolution);
  int count = 0;
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (auto w = windows.add(angle[i], value[i])) {
      sum += w->tsa;
      ++count;
    }
  }
  if (revolutions) *revolutions = count;
  if (count == 0)
    throw std::invalid_argument("time_synchronous_average: the samples cover no whole revolution (aligned to angle 0)");
  return sum / count;
}

}  // namespace gear_dynamics
