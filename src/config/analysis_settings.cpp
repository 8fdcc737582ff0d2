#include "gear_dynamics/config/analysis_settings.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/section_reader.hpp"

namespace gear_dynamics {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

std::size_t BinSpec::bins() const { return static_cast<std::size_t>(std::llround((hi - lo) / width)); }

std::vector<double> BinSpec::edges() const {
  const std::size_t n = bins();
  const double step = (hi - lo) / static_cast<double>(n);
  std::vector<double> e(n + 1);
  for (std::size_t i = 0; i < n; ++i) e[i] = lo + static_cast<double>(i) * step;
  e[n] = hi;
  return e;
}

void validate(const BinSpec& s, const std::string& name) {
  std::ostringstream e;
  e.precision(12);
  if (!(std::isfinite(s.lo) && std::isfinite(s.hi) && s.lo < s.hi)) {
    e << name << " = [" << s.lo << ", " << s.hi << "] is not an interval; needs finite lo < hi";
  } else if (!(s.width > 0.0 && s.width <= s.hi - s.lo)) {
    e << name << ".width = " << s.width << " is out of range; allowed (0, hi - lo = " << s.hi - s.lo << "]";
  } else {
    const double n = (s.hi - s.lo) / s.width;
    if (std::abs(n - std::round(n)) > 1e-6 * n || n > 1e6) {
      e << name << ": (hi - lo) / width = " << n << " is not a whole number of bins (at most 1e6)";
    } else {
      return;
    }
  }
  throw std::invalid_argument(e.str());
}

AnalysisSettings parse_analysis_settings(const YAML::Node& root) {
  const YAML::Node a = root["analysis"];
  if (!a || !a.IsMap()) throw ConfigError("invalid configuration: missing section 'analysis' (a map)");
  std::vector<std::string> errors;
  SectionReader in(a, "analysis", errors);
  AnalysisSettings s;
  if (const auto v = in.number("confidence", 0, 1, false, "-", /*open_lo=*/true, /*open_hi=*/true)) s.confidence = *v;
  const auto interval = [&](const char* key, const std::string& unit, Interval& out) {
    const auto v = in.numbers(key, -kInf, kInf, unit, 2);
    if (!v) return;
    out = {(*v)[0], (*v)[1]};
    if (!(out.lo <= out.hi))
      in.error(key, " = [" + SectionReader::text_of(out.lo) + ", " + SectionReader::text_of(out.hi) +
                        "] is empty; allowed lo <= hi, in " + unit);
  };
  const auto bins = [&](const char* key, const std::string& unit, BinSpec& out) {
    const auto v = in.numbers(key, -kInf, kInf, unit + " ([lo, hi, width])", 3);
    if (!v) return;
    out = {(*v)[0], (*v)[1], (*v)[2]};
    try {
      validate(out, std::string("analysis.") + key);
    } catch (const std::invalid_argument& ex) {
      errors.emplace_back(ex.what());
    }
  };
  interval("delta_interval", "m", s.delta_interval);
  interval("delta_dot_interval", "m/s", s.delta_dot_interval);
  bins("delta_bins", "m", s.delta_bins);
  bins("delta_dot_bins", "m/s", s.delta_dot_bins);
  bins("joint_delta_bins", "m", s.joint_delta_bins);
  bins("joint_delta_dot_bins", "m/s", s.joint_delta_dot_bins);
  if (const auto v = in.numbers("joint_times", 0, kInf, "s")) s.joint_times = *v;
  in.finish();
  detail::throw_if_errors(errors);
  return s;
}

YAML::Node to_yaml(const AnalysisSettings& s) {
  YAML::Node a;
  const auto list = [](std::initializer_list<double> v) {
    YAML::Node n;
    for (double x : v) n.push_back(x);
    n.SetStyle(YAML::EmitterStyle::Flow);
    return n;
  };
  a["confidence"] = s.confidence;
  a["delta_interval"] = list({s.delta_interval.lo, s.delta_interval.hi});
  a["delta_dot_interval"] = list({s.delta_dot_interval.lo, s.delta_dot_interval.hi});
  a["delta_bins"] = list({s.delta_bins.lo, s.delta_bins.hi, s.delta_bins.width});
  a["delta_dot_bins"] = list({s.delta_dot_bins.lo, s.delta_dot_bins.hi, s.delta_dot_bins.width});
  a["joint_delta_bins"] = list({s.joint_delta_bins.lo, s.joint_delta_bins.hi, s.joint_delta_bins.width});
  a["joint_delta_dot_bins"] = list({s.joint_delta_dot_bins.lo, s.joint_delta_dot_bins.hi, s.joint_delta_dot_bins.width});
  YAML::Node t;
  for (double x : s.joint_times) t.push_back(x);
  t.SetStyle(YAML::EmitterStyle::Flow);
  a["joint_times"] = t;
  YAML::Node root;
  root["analysis"] = a;
  return root;
}

}  // namespace gear_dynamics
