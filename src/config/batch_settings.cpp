#include "gear_dynamics/config/batch_settings.hpp"

#include <cmath>
#include <cstdio>
#include <set>


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

std::string s1_run_label(double mu) { return mu_label(mu) + "_S1"; }

std::string phase_run_label(double mu, std::uint64_t phase) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_phase%02llu", static_cast<unsigned long long>(phase));
  return mu_label(mu) + buf;
}

std::string realization_run_label(double mu, std::uint64_t realization) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_r%05llu", static_cast<unsigned long long>(realization));
  return mu_label(mu) + buf;
}

// At most this many shards; shard_index lies below shard_count.
constexpr double kMaxShards = 1e6;

const Section<BatchSettings>& batch_section() {
  static const Section<BatchSettings> section =
      Section<BatchSettings>("monte_carlo", "monte_carlo.")
          // What the batch holds: the manifest records these and resume compares them.
          .key("mu", GD_MEMBER(mu), closed(0, kMaxFrictionCoefficient), "-",
               "friction coefficients, distinct in the 4th decimal (they name the runs)")
          .key("realizations", GD_MEMBER(realizations), closed(1, 1e6), "-", "R, stochastic realizations 0..R-1 per mu (S2 = 0, S3 = 1)")
          .key("phase_ensemble", GD_MEMBER(phase_ensemble), "the deterministic phase ensemble per mu: S1 at phi0 = j phi_n / 64, j = 0..63")
          .key("record_rate", GD_MEMBER(record_rate), open_closed(0, 1e9), "Hz",
               "GearState series of S1 and of the realizations < record_realizations; 1/(rate h) a whole number of steps that divides T/h")
          .key("record_realizations", GD_MEMBER(record_realizations), closed(0, 1e6), "-",
               "realizations recorded at record_rate (S2, S3); at most realizations")
          .key("sparse_record_rate", GD_MEMBER(sparse_record_rate), closed(0, 1e9), "Hz",
               "series of every other run; 0 = none, else it fits the grid as record_rate does")
          // How it runs: no effect on any bag's content.
          .key("output_dir", GD_MEMBER(output_dir), "the batch folder; a relative path is taken from the node's working directory ($ROS_HOME under roslaunch)")
          .key("overwrite", GD_MEMBER(overwrite), "replace a folder that holds another batch")
          .key("shard_index", GD_MEMBER(shard_index), closed(0, kMaxShards - 1), "-",
               "this process runs the runs i with i mod shard_count = shard_index; below shard_count")
          .key("shard_count", GD_MEMBER(shard_count), closed(1, kMaxShards), "-", "number of shards")
          .key("block_lanes", GD_MEMBER(block_lanes), closed(1, 4096), "lanes", "runs stepped together (SIMD lanes; larger blocks amortise the per-step work)")
          .key("threads", GD_MEMBER(threads), closed(0, 1024), "-", "worker threads; 0 = all cores available to the process");
  return section;
}

BatchSettings parse_batch_settings(const YAML::Node& section, const ModelConfig& model) {
  if (!section || !section.IsMap())
    throw ConfigError("invalid configuration: missing section 'monte_carlo' (a map of the batch settings)");
  std::vector<std::string> errors;
  SectionReader in(section, "monte_carlo.", errors);
  BatchSettings s;
  batch_section().read(in, s);
  // Checks between keys, each only when the keys it needs are good (each problem is reported once).
  if (in.ok("mu")) {
    std::set<std::string> names;
    for (double m : s.mu)
      if (!names.insert(mu_label(m)).second)
        in.error("mu", " = " + detail::show(section["mu"]) + " repeats " + SectionReader::text_of(m) +
                           " (values must differ in the 4th decimal, which names the runs)");
  }
  if (in.ok("record_rate")) record_interval(in, "record_rate", s.record_rate, model);
  if (in.ok("sparse_record_rate")) record_interval(in, "sparse_record_rate", s.sparse_record_rate, model);
  if (in.ok("realizations") && in.ok("record_realizations") && s.record_realizations > s.realizations)
    in.error("record_realizations", " = " + std::to_string(s.record_realizations) + " is out of range; allowed [0, " +
                                        std::to_string(s.realizations) + "] (integer) (at most realizations)");
  if (in.ok("shard_count") && in.ok("shard_index") && s.shard_index >= s.shard_count)
    in.error("shard_index", " = " + std::to_string(s.shard_index) + " is out of range; allowed [0, " +
                                std::to_string(s.shard_count - 1) + "] (integer) (below shard_count)");
  in.finish({"sweep"});  // optional, a list of axes: read by read_sweep (config/sweep.hpp)
  read_sweep(section, s.mu, s.sweep, errors);
  detail::throw_if_errors(errors);
  return s;
}

YAML::Node content_yaml(const BatchSettings& s) {
  const YAML::Node all = batch_section().to_yaml(s);
  YAML::Node n;
  for (const char* key : {"mu", "realizations", "phase_ensemble", "record_rate", "record_realizations", "sparse_record_rate"})
    n[key] = all[key];
  return n;
}

}  // namespace gear_dynamics
