#include "gear_dynamics/config/analysis_settings.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

// An interval is the list [lo, hi], a BinSpec [lo, hi, width].
template <>
struct Codec<Interval> {
  static constexpr KeyKind kind = KeyKind::RealList;
  static constexpr std::size_t size = 2;
  static void set(Interval& m, const Value& v) { m = {v.numbers[0], v.numbers[1]}; }
  static YAML::Node get(const Interval& m) { return flow_list(std::vector<double>{m.lo, m.hi}); }
};
template <>
struct Codec<BinSpec> {
  static constexpr KeyKind kind = KeyKind::RealList;
  static constexpr std::size_t size = 3;
  static void set(BinSpec& m, const Value& v) { m = {v.numbers[0], v.numbers[1], v.numbers[2]}; }
  static YAML::Node get(const BinSpec& m) { return flow_list(std::vector<double>{m.lo, m.hi, m.width}); }
};

const Section<AnalysisSettings>& analysis_section() {
  static const Section<AnalysisSettings> section =
      Section<AnalysisSettings>("analysis", "analysis.")
          .key("confidence", GD_MEMBER(confidence), open(0, 1), "-", "level of every interval (Wilson, median)")
          .key("delta_interval", GD_MEMBER(delta_interval), any_number(), "m",
               "Table 4 safety interval [lo, hi] of delta(T), closed, lo <= hi")
          .key("delta_dot_interval", GD_MEMBER(delta_dot_interval), any_number(), "m/s",
               "Table 4 safety interval [lo, hi] of delta_dot(T), closed, lo <= hi")
          .key("delta_bins", GD_MEMBER(delta_bins), any_number(), "m",
               "Fig. 11 histogram of delta(T) [lo, hi, width]: lo < hi, width in (0, hi - lo], a whole number of bins <= 1e6")
          .key("delta_dot_bins", GD_MEMBER(delta_dot_bins), any_number(), "m/s", "Fig. 12 histogram of delta_dot(T) [lo, hi, width], as delta_bins")
          .key("joint_delta_bins", GD_MEMBER(joint_delta_bins), any_number(), "m",
               "Fig. 10 joint histogram, delta axis [lo, hi, width], as delta_bins")
          .key("joint_delta_dot_bins", GD_MEMBER(joint_delta_dot_bins), any_number(), "m/s",
               "Fig. 10 joint histogram, delta_dot axis [lo, hi, width], as delta_bins")
          .key("joint_times", GD_MEMBER(joint_times), closed_open(0, kInf), "s",
               "Fig. 10 snapshot times, each among the batch's run.snapshot_times (checked when the runs are analysed)")
          .key("first_passage_settle", GD_MEMBER(first_passage_settle), closed_open(0, kInf), "s",
               "settling time: first passage out of the safe set counts exits at recorded times >= this (none computed if no time is)")
          .key("spectrum_transient", GD_MEMBER(spectrum_transient), closed_open(0, kInf), "s",
               "start-up dropped before the Welch PSD of the dense realizations' delta (none computed if less than a mesh period is left)")
          .key("poincare_transient", GD_MEMBER(poincare_transient), closed_open(0, kInf), "s",
               "start-up dropped before the Poincare section of the phase ensemble (points at t < this are not used)")
          .key("kde", GD_MEMBER(kde), "Gaussian KDEs (Silverman's bandwidth) beside the histograms of Figs. 11 and 12");
  return section;
}

AnalysisSettings parse_analysis_settings(const YAML::Node& root) {
  std::vector<std::string> errors;
  const AnalysisSettings s = read_analysis_settings(root, errors);
  detail::throw_if_errors(errors);
  return s;
}

AnalysisSettings read_analysis_settings(const YAML::Node& root, std::vector<std::string>& errors) {
  AnalysisSettings s;
  const YAML::Node a = root["analysis"];
  if (!a || !a.IsMap()) {
    errors.push_back("missing section 'analysis' (a map of the analysis settings, config/aggregator.yaml)");
    return s;
  }
  SectionReader in(a, "analysis.", errors);
  analysis_section().read(in, s);
  // What a list's elements must satisfy together, for the lists that are good.
  const auto interval = [&](const char* key, const char* unit, const Interval& v) {
    if (in.ok(key) && !(v.lo <= v.hi))
      in.error(key, " = [" + SectionReader::text_of(v.lo) + ", " + SectionReader::text_of(v.hi) +
                        "] is empty; allowed lo <= hi, in " + unit);
  };
  const auto bins = [&](const char* key, const BinSpec& v) {
    try {
      if (in.ok(key)) validate(v, in.prefix() + key);
    } catch (const std::invalid_argument& ex) {
      errors.emplace_back(ex.what());
    }
  };
  interval("delta_interval", "m", s.delta_interval);
  interval("delta_dot_interval", "m/s", s.delta_dot_interval);
  bins("delta_bins", s.delta_bins);
  bins("delta_dot_bins", s.delta_dot_bins);
  bins("joint_delta_bins", s.joint_delta_bins);
  bins("joint_delta_dot_bins", s.joint_delta_dot_bins);
  in.finish();
  return s;
}

YAML::Node to_yaml(const AnalysisSettings& s) {
  YAML::Node root;
  root["analysis"] = analysis_section().to_yaml(s);
  return root;
}

}  // namespace gear_dynamics
