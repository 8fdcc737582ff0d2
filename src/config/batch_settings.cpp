#include "gear_dynamics/config/batch_settings.hpp"

#include <cmath>
#include <cstdio>
#include <set>

#include "gear_dynamics/config/section_reader.hpp"

namespace gear_dynamics {

namespace {

// Grid steps between recorded states at `rate` [Hz]; `rate` must give a whole number of steps
// that divides the run, so the series ends at T.
std::int64_t record_interval(SectionReader& in, const char* key, double rate, const ModelConfig& model) {
  if (rate <= 0.0) return 0;
  const double h = model.run.time_step, k = 1.0 / (rate * h);
  const std::int64_t every = std::llround(k), total = model.run.steps();
  if (every >= 1 && std::abs(k - static_cast<double>(every)) <= 1e-9 * k && total % every == 0)
    return every;
  in.error(key, " = " + SectionReader::text_of(rate) + " Hz does not fit the grid: 1 / (rate x run.time_step) = " +
                    SectionReader::text_of(k) + " steps, which must be a whole number >= 1 that divides the run's " +
                    std::to_string(total) + " steps (e.g. " + SectionReader::text_of(1.0 / h) + ", " +
                    SectionReader::text_of(0.1 / h) + " or " + SectionReader::text_of(0.001 / h) + " Hz)");
  return 0;
}

}  // namespace

std::string mu_label(double mu) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "mu%.4f", mu);
  return buf;
}

BatchSettings parse_batch_settings(const YAML::Node& section, const ModelConfig& model) {
  if (!section || !section.IsMap())
    throw ConfigError("invalid configuration: missing section 'monte_carlo' (a map of the batch settings)");
  std::vector<std::string> errors;
  YAML::Node rest = YAML::Clone(section);  // `sweep` is optional and read by read_sweep (config/sweep.hpp)
  rest.remove("sweep");
  SectionReader in(rest, "monte_carlo", errors);
  BatchSettings s;
  // A key that is missing or bad keeps its default below; the checks that depend on it are left
  // out, so each problem is reported once.
  if (const auto mu = in.numbers("mu", 0.0, kMaxFrictionCoefficient, "-")) {
    s.mu = *mu;
    std::set<std::string> names;
    for (double m : s.mu)
      if (!names.insert(mu_label(m)).second)
        in.error("mu", " = " + detail::show(section["mu"]) + " repeats " + SectionReader::text_of(m) +
                           " (values must differ in the 4th decimal, which names the runs)");
  }
  const auto realizations = in.number("realizations", 1, 1e6, true, "-");
  if (realizations) s.realizations = static_cast<std::uint32_t>(*realizations);
  if (const auto v = in.flag("phase_ensemble")) s.phase_ensemble = *v;
  // record_interval checks that a rate fits the grid (at most one state per step).
  if (const auto v = in.number("record_rate", 0, 1e9, false, "Hz", /*open_lo=*/true)) {
    s.record_rate = *v;
    record_interval(in, "record_rate", s.record_rate, model);
  }
  if (const auto v = in.number("record_realizations", 0, realizations ? *realizations : 1e6, true, "-"))
    s.record_realizations = static_cast<std::uint32_t>(*v);
  if (const auto v = in.number("sparse_record_rate", 0, 1e9, false, "Hz (0 = no series)")) {
    s.sparse_record_rate = *v;
    record_interval(in, "sparse_record_rate", s.sparse_record_rate, model);
  }
  if (const auto v = in.text("output_dir")) s.output_dir = *v;
  if (const auto v = in.flag("overwrite")) s.overwrite = *v;
  const auto shard_count = in.number("shard_count", 1, 1e6, true, "-");
  if (shard_count) s.shard_count = static_cast<int>(*shard_count);
  if (const auto v = in.number("shard_index", 0, shard_count ? *shard_count - 1 : 1e6, true, "- (below shard_count)"))
    s.shard_index = static_cast<int>(*v);
  if (const auto v = in.number("block_lanes", 1, 4096, true, "lanes")) s.block_lanes = static_cast<int>(*v);
  if (const auto v = in.number("threads", 0, 1024, true, "threads (0 = all cores)")) s.threads = static_cast<int>(*v);
  in.finish();
  read_sweep(section, s.mu, s.sweep, errors);
  detail::throw_if_errors(errors);
  return s;
}

YAML::Node content_yaml(const BatchSettings& s) {
  YAML::Node n;
  for (double mu : s.mu) n["mu"].push_back(mu);
  n["mu"].SetStyle(YAML::EmitterStyle::Flow);
  n["realizations"] = s.realizations;
  n["phase_ensemble"] = s.phase_ensemble;
  n["record_rate"] = s.record_rate;
  n["record_realizations"] = s.record_realizations;
  n["sparse_record_rate"] = s.sparse_record_rate;
  return n;
}

}  // namespace gear_dynamics
