// Streaming statistics of large ensembles: the Monte Carlo batch runner (montecarlo/batch.hpp: its
// study grid, blocks of lanes, TBB threads, stop flag and progress counter) with a sink that folds
// every recorded state into per-time histograms and safety counters instead of keeping the paths.
// Every accumulator is an integer count or a value kept by run, so the numbers do not depend on
// the thread count or the order in which blocks finish.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gear_dynamics/config/analysis_settings.hpp"
#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/sweep.hpp"
#include "gear_dynamics/maths/statistics.hpp"
#include "gear_dynamics/montecarlo/batch.hpp"
#include "module.hpp"

namespace py = pybind11;
namespace gd = gear_dynamics;

namespace gear_dynamics::python {
namespace {

// Per recorded time, the counts of one quantity in the bins of `spec` (numpy's rule: [e_i, e_i+1),
// the last bin closed) with the values below e_0 and above e_n (NaN among them) apart.
class TimeHistogram {
 public:
  TimeHistogram(const BinSpec& spec, std::size_t times)
      : edges_(spec.edges()), bins_(edges_.size() - 1), counts_(times * (bins_ + 2), 0) {}

  void add(std::size_t time, double x) {
    std::uint64_t* row = counts_.data() + time * (bins_ + 2);
    if (!(x >= edges_.front())) {
      ++row[x < edges_.front() ? 0 : bins_ + 1];  // NaN above, as numpy sorts it last
    } else if (x > edges_.back()) {
      ++row[bins_ + 1];
    } else {
      const auto i = static_cast<std::size_t>(std::upper_bound(edges_.begin(), edges_.end(), x) - edges_.begin());
      ++row[std::min(i, bins_)];  // i - 1 is the bin, shifted by the 'below' slot; x == e_n: the last bin
    }
  }

  // The k-th smallest value, k = max(1, ceil(p n)), placed in its bin by its rank among the bin's
  // counts: within one bin width of the true order statistic; NaN when it lies outside the bins.
  double quantile(std::size_t time, double p) const {
    const std::uint64_t* row = counts_.data() + time * (bins_ + 2);
    std::uint64_t n = 0;
    for (std::size_t i = 0; i < bins_ + 2; ++i) n += row[i];
    if (n == 0) return std::numeric_limits<double>::quiet_NaN();
    const auto k = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(p * static_cast<double>(n))));
    std::uint64_t below = row[0];
    if (k <= below) return std::numeric_limits<double>::quiet_NaN();
    for (std::size_t b = 0; b < bins_; ++b) {
      const std::uint64_t c = row[b + 1];
      if (k <= below + c) {
        const double rank = (static_cast<double>(k - below) - 0.5) / static_cast<double>(c);
        return edges_[b] + rank * (edges_[b + 1] - edges_[b]);
      }
      below += c;
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

  std::size_t bins() const { return bins_; }
  const std::vector<double>& edges() const { return edges_; }
  const std::vector<std::uint64_t>& counts() const { return counts_; }  // [time][below, bins..., above]

 private:
  std::vector<double> edges_;
  std::size_t bins_;
  std::vector<std::uint64_t> counts_;
};

struct StreamOptions {
  std::vector<double> probabilities;  // quantiles asked for, each in [0, 1]
  BinSpec delta_bins, delta_dot_bins, center_distance_bins;
  Interval delta_interval, delta_dot_interval;  // the safe set
  double confidence = kConfidence;
};

// One study point's statistics of its stochastic realizations, S1's path and every run's result.
struct PointStatistics {
  PointStatistics(const StreamOptions& o, std::size_t times, std::size_t realizations)
      : delta(o.delta_bins, times), delta_dot(o.delta_dot_bins, times), center_distance(o.center_distance_bins, times),
        inside_joint(times, 0), inside_delta(times, 0), inside_velocity(times, 0), lanes(times, 0),
        s1_delta(times, NaN), s1_delta_dot(times, NaN), s1_phi(times, NaN), s1_center_distance(times, NaN),
        results(realizations) {}
  static constexpr double NaN = std::numeric_limits<double>::quiet_NaN();
  std::mutex mutex;  // blocks of one point record concurrently
  TimeHistogram delta, delta_dot, center_distance;
  std::vector<std::uint64_t> inside_joint, inside_delta, inside_velocity, lanes;
  std::vector<double> s1_delta, s1_delta_dot, s1_phi, s1_center_distance;
  std::optional<RunResult> s1_result;
  std::vector<std::optional<RunResult>> results;  // by realization
};

class StatisticsSink : public BatchSink {
 public:
  StatisticsSink(const StreamOptions& o, const Study& study, std::size_t times, std::size_t realizations,
                 std::int64_t record_every)
      : options_(o), record_every_(record_every) {
    for (std::size_t i = 0; i < study.points.size(); ++i)
      points_.push_back(std::make_unique<PointStatistics>(o, times, realizations));
  }
  void started(const std::vector<RunSpec>&) override {}
  void recorded(const std::vector<RunSpec>& block, const Ensemble& e, const Eigen::ArrayXd& d) override {
    const auto j = static_cast<std::size_t>(e.step_index() / record_every_);
    std::unique_lock<std::mutex> lock;
    for (std::size_t i = 0; i < block.size(); ++i) {
      // Points that share a schedule (a load.sigma axis, ...) share blocks: each lane its point.
      PointStatistics& p = *points_.at(block[i].point);
      if (lock.mutex() != &p.mutex) lock = std::unique_lock<std::mutex>(p.mutex);
      const double x = e.delta()[static_cast<Eigen::Index>(i)], v = e.velocity()[static_cast<Eigen::Index>(i)];
      const double di = d[static_cast<Eigen::Index>(i)];
      if (block[i].kind == RunKind::S1) {
        p.s1_delta[j] = x;
        p.s1_delta_dot[j] = v;
        p.s1_phi[j] = e.load()[static_cast<Eigen::Index>(i)];
        p.s1_center_distance[j] = di;
        continue;
      }
      p.delta.add(j, x);
      p.delta_dot.add(j, v);
      p.center_distance.add(j, di);
      const bool in_delta = options_.delta_interval.contains(x), in_velocity = options_.delta_dot_interval.contains(v);
      p.inside_delta[j] += in_delta;
      p.inside_velocity[j] += in_velocity;
      p.inside_joint[j] += in_delta && in_velocity;
      ++p.lanes[j];
    }
  }
  void finished(const std::vector<RunSpec>& block, const std::vector<RunResult>& results) override {
    std::unique_lock<std::mutex> lock;
    for (std::size_t i = 0; i < block.size(); ++i) {
      PointStatistics& p = *points_.at(block[i].point);
      if (lock.mutex() != &p.mutex) lock = std::unique_lock<std::mutex>(p.mutex);
      if (block[i].kind == RunKind::S1) p.s1_result = results[i];
      else p.results.at(block[i].index) = results[i];
    }
  }
  void abandoned(const std::vector<RunSpec>&) override {}
  std::vector<std::unique_ptr<PointStatistics>>& points() { return points_; }

 private:
  const StreamOptions& options_;
  std::int64_t record_every_;
  std::vector<std::unique_ptr<PointStatistics>> points_;
};

py::array_t<double> array(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

// (times, bins) counts without the outside slots, and the outside counts (times, 2): below, above.
py::dict histogram_dict(const TimeHistogram& h, std::size_t times, const std::vector<double>& probabilities) {
  const auto nt = static_cast<py::ssize_t>(times), nb = static_cast<py::ssize_t>(h.bins());
  const auto np = static_cast<py::ssize_t>(probabilities.size());
  py::array_t<std::uint64_t> counts({nt, nb}), outside({nt, py::ssize_t{2}});
  py::array_t<double> q({nt, np});
  auto mc = counts.mutable_unchecked<2>();
  auto mo = outside.mutable_unchecked<2>();
  auto mq = q.mutable_unchecked<2>();
  for (py::ssize_t j = 0; j < nt; ++j) {
    const std::uint64_t* row = h.counts().data() + static_cast<std::size_t>(j) * (h.bins() + 2);
    mo(j, 0) = row[0];
    mo(j, 1) = row[h.bins() + 1];
    for (py::ssize_t b = 0; b < nb; ++b) mc(j, b) = row[b + 1];
    for (py::ssize_t k = 0; k < np; ++k) mq(j, k) = h.quantile(static_cast<std::size_t>(j), probabilities[static_cast<std::size_t>(k)]);
  }
  py::dict out;
  out["edges"] = array(h.edges());
  out["counts"] = counts;
  out["outside"] = outside;
  out["quantiles"] = q;
  return out;
}

py::dict proportion_dict(const std::vector<std::uint64_t>& inside, const std::vector<std::uint64_t>& lanes,
                         double confidence) {
  std::vector<double> estimate, low, high;
  for (std::size_t j = 0; j < inside.size(); ++j) {
    const Proportion p = wilson(inside[j], lanes[j], confidence);
    estimate.push_back(p.estimate);
    low.push_back(p.low);
    high.push_back(p.high);
  }
  py::dict out;
  out["probability"] = array(estimate);
  out["low"] = array(low);
  out["high"] = array(high);
  out["count"] = py::array_t<std::uint64_t>(static_cast<py::ssize_t>(inside.size()), inside.data());
  return out;
}

py::dict result_columns(const std::vector<std::optional<RunResult>>& results) {
  auto column = [&](auto get) {
    std::vector<double> v;
    for (const auto& r : results) v.push_back(r ? get(*r) : std::numeric_limits<double>::quiet_NaN());
    return array(v);
  };
  py::dict s;
  s["center_distance"] = column([](const RunResult& r) { return r.center_distance; });
  s["delta_range"] = column([](const RunResult& r) { return r.delta_range; });
  s["delta_dot_range"] = column([](const RunResult& r) { return r.delta_dot_range; });
  s["steady_state_time"] = column([](const RunResult& r) { return r.steady_state_time; });
  s["steady_state_time_fine"] = column([](const RunResult& r) { return r.steady_state_time_fine; });
  s["reached_steady_state"] = column([](const RunResult& r) { return r.reached_steady_state ? 1.0 : 0.0; });
  s["final_delta"] = column([](const RunResult& r) { return r.final_delta; });
  s["final_delta_dot"] = column([](const RunResult& r) { return r.final_delta_dot; });
  s["final_load"] = column([](const RunResult& r) { return r.final_load; });
  return s;
}

BinSpec bin_spec(const std::vector<double>& v, const std::string& name) {
  if (v.size() != 3) throw std::invalid_argument(name + " must be (lo, hi, width), got " + std::to_string(v.size()) + " values");
  const BinSpec s{v[0], v[1], v[2]};
  validate(s, name);
  return s;
}

Interval interval(const std::vector<double>& v, const std::string& name) {
  if (v.size() != 2 || !(v[0] <= v[1]))
    throw std::invalid_argument(name + " must be (lo, hi) with lo <= hi");
  return {v[0], v[1]};
}

// The batch settings of a statistics run, through parse_batch_settings so that the grid (its keys,
// ranges and the friction axis) and the record rate are validated as a batch's.
BatchSettings stream_settings(const ModelConfig& model, const std::vector<double>& mu, const std::string& sweep_yaml,
                              int realizations, double rate, int threads, int block_lanes) {
  YAML::Node s;
  for (double m : mu) s["mu"].push_back(m);
  s["realizations"] = realizations;
  s["phase_ensemble"] = false;
  s["record_rate"] = rate;  // S1's path
  s["record_realizations"] = 0;
  s["sparse_record_rate"] = rate;  // every realization
  if (!sweep_yaml.empty()) s["sweep"] = YAML::Load(sweep_yaml);
  s["output_dir"] = "unused";
  s["overwrite"] = false;
  s["shard_index"] = 0;
  s["shard_count"] = 1;
  s["block_lanes"] = block_lanes;
  s["threads"] = threads;
  return parse_batch_settings(s, model);
}

// Runs the batch on a thread of its own while this (Python's main) thread, GIL released between
// looks, reports progress and turns a pending signal or a progress callback's exception into
// `stop`: Ctrl-C ends the run at the blocks' next recorded step.
void run_interruptible(const Study& study, const std::vector<RunSpec>& runs, const BatchSettings& settings,
                       BatchSink& sink, const std::function<void(std::int64_t, std::int64_t)>& progress) {
  BatchControl control;
  const std::int64_t total = static_cast<std::int64_t>(runs.size()) * study.base.run.steps();
  std::future<void> done;
  std::exception_ptr python_error;
  {
    py::gil_scoped_release release;
    done = std::async(std::launch::async, [&] { run_batch(study, runs, settings, sink, control); });
    while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      py::gil_scoped_acquire gil;
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (progress) progress(control.realization_steps.load(), total);
      } catch (...) {
        python_error = std::current_exception();
        control.stop = true;
        break;
      }
    }
    done.wait();
  }
  if (python_error) std::rethrow_exception(python_error);
  done.get();  // the batch's own error (a diverging run, ...)
  if (progress) progress(total, total);
}

py::dict ensemble_statistics(const std::vector<std::string>& files, const std::vector<std::string>& sets,
                             std::optional<double> mu, std::optional<long long> seed, const std::string& sweep_yaml,
                             int realizations, double rate, int threads, int block_lanes,
                             const std::vector<double>& probabilities, std::optional<std::vector<double>> delta_bins,
                             std::optional<std::vector<double>> delta_dot_bins,
                             const std::vector<double>& center_distance_bins,
                             std::optional<std::vector<double>> delta_interval,
                             std::optional<std::vector<double>> delta_dot_interval,
                             const std::function<void(std::int64_t, std::int64_t)>& progress) {
  if (realizations < 1) throw std::invalid_argument("realizations = " + std::to_string(realizations) + ": must be >= 1");
  if (!(rate > 0)) throw std::invalid_argument("rate = " + std::to_string(rate) + " Hz: must be > 0 (the statistics are over recorded times)");
  for (double p : probabilities)
    if (!(p >= 0 && p <= 1)) throw std::invalid_argument("quantiles: " + std::to_string(p) + " is outside [0, 1]");
  const ModelConfig model = parse_config(model_root(files, sets, mu, seed));
  const AnalysisSettings analysis;  // the aggregator's defaults (config/aggregator.yaml)
  StreamOptions o;
  o.probabilities = probabilities;
  o.delta_bins = delta_bins ? bin_spec(*delta_bins, "delta_bins") : analysis.delta_bins;
  o.delta_dot_bins = delta_dot_bins ? bin_spec(*delta_dot_bins, "delta_dot_bins") : analysis.delta_dot_bins;
  o.center_distance_bins = bin_spec(center_distance_bins, "center_distance_bins");
  o.delta_interval = delta_interval ? interval(*delta_interval, "delta_interval") : analysis.delta_interval;
  o.delta_dot_interval = delta_dot_interval ? interval(*delta_dot_interval, "delta_dot_interval") : analysis.delta_dot_interval;
  o.confidence = analysis.confidence;

  const BatchSettings settings =
      stream_settings(model, {model.friction_coefficient}, sweep_yaml, realizations, rate, threads, block_lanes);
  const Study study = make_study(model, settings);
  const std::vector<RunSpec> runs = plan_runs(study, settings);
  const std::int64_t record_every = runs.front().record_every;
  const auto times = static_cast<std::size_t>(model.run.steps() / record_every) + 1;
  StatisticsSink sink(o, study, times, static_cast<std::size_t>(realizations), record_every);
  run_interruptible(study, runs, settings, sink, progress);

  std::vector<double> t(times);
  for (std::size_t j = 0; j < times; ++j) t[j] = grid_time(static_cast<std::int64_t>(j) * record_every, model.run.time_step);
  py::list points;
  for (std::size_t i = 0; i < study.points.size(); ++i) {
    PointStatistics& p = *sink.points()[i];
    py::dict point;
    py::dict values;
    const std::vector<std::string> keys = study.keys();
    for (std::size_t a = 0; a < keys.size(); ++a) values[py::str(keys[a])] = study.points[i].values[a];
    point["grid"] = values;
    point["t"] = array(t);
    point["delta"] = histogram_dict(p.delta, times, probabilities);
    point["delta_dot"] = histogram_dict(p.delta_dot, times, probabilities);
    point["center_distance"] = histogram_dict(p.center_distance, times, probabilities);
    py::dict safety;
    safety["joint"] = proportion_dict(p.inside_joint, p.lanes, o.confidence);
    safety["delta"] = proportion_dict(p.inside_delta, p.lanes, o.confidence);
    safety["delta_dot"] = proportion_dict(p.inside_velocity, p.lanes, o.confidence);
    safety["realizations"] = py::array_t<std::uint64_t>(static_cast<py::ssize_t>(times), p.lanes.data());
    point["safety"] = safety;
    py::dict s1;
    s1["delta"] = array(p.s1_delta);
    s1["delta_dot"] = array(p.s1_delta_dot);
    s1["phi"] = array(p.s1_phi);
    s1["center_distance"] = array(p.s1_center_distance);
    s1["summary"] = result_columns({p.s1_result});
    point["s1"] = s1;
    point["summary"] = result_columns(p.results);
    points.append(point);
  }
  py::dict out;
  out["axes"] = study.keys();
  out["points"] = points;
  out["quantiles"] = probabilities;
  out["delta_interval"] = std::vector<double>{o.delta_interval.lo, o.delta_interval.hi};
  out["delta_dot_interval"] = std::vector<double>{o.delta_dot_interval.lo, o.delta_dot_interval.hi};
  out["seed"] = model.seed;
  out["time_step"] = model.run.time_step;
  out["duration"] = model.run.duration;
  return out;
}

}  // namespace

void bind_ensemble(py::module_& m) {
  m.def("ensemble_statistics", &ensemble_statistics, py::arg("files"), py::arg("sets"), py::arg("mu"), py::arg("seed"),
        py::arg("sweep_yaml"), py::arg("realizations"), py::arg("rate"), py::arg("threads"), py::arg("block_lanes"),
        py::arg("quantiles"), py::arg("delta_bins"), py::arg("delta_dot_bins"), py::arg("center_distance_bins"),
        py::arg("delta_interval"), py::arg("delta_dot_interval"), py::arg("progress"),
        "Streaming statistics of the realizations of every point of a study grid.");
}

}  // namespace gear_dynamics::python
