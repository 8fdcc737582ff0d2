#include "gear_dynamics/ros/monte_carlo_node.hpp"

#include <ros/ros.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>

#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/montecarlo/batch.hpp"
#include "gear_dynamics/ros/batch_io.hpp"
#include "gear_dynamics/ros/conversions.hpp"
#include "gear_dynamics/ros/stop_signal.hpp"

namespace gear_dynamics {

namespace {

std::string clock_text(double seconds) {
  if (!(seconds >= 0)) return "?";
  const long s = std::lround(seconds);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  return buf;
}

}  // namespace

int MonteCarloNode::init() {
  try {
    model_ = load_model_config(pnh_);
    settings_ = parse_batch_settings(yaml_from_parameters(pnh_, {"monte_carlo"})["monte_carlo"], model_);
    study_ = make_study(model_, settings_);  // every point validated before anything runs
    runs_ = shard_runs(plan_runs(study_, settings_), settings_.shard_index, settings_.shard_count);
    todo_ = prepare_folder(study_, settings_, runs_);
    ROS_INFO("gear_monte_carlo: %s", instruction_set_description().c_str());  // refuses a bad GEAR_DYNAMICS_ISA
  } catch (const std::exception& e) {
    if (const int sig = stop_signal()) {  // what failed was interrupted: a stop, not bad input
      ROS_WARN("gear_monte_carlo: stopped by %s while starting, before any run", stop_signal_name());
      return 128 + sig;
    }
    ROS_FATAL("gear_monte_carlo: %s", e.what());
    return 2;
  }
  progress_pub_ = pnh_.advertise<BatchProgress>("progress", 1, true);
  return 0;
}

int MonteCarloNode::run() {
  const double steps = static_cast<double>(model_.run.steps());
  ROS_INFO("gear_monte_carlo: shard %d of %d into '%s': %zu runs, %zu complete, %zu to do "
           "(%zu points: %zu mu%s; S1%s, %u realizations; T = %g s, h = %g s; %d threads, %d lanes per block)",
           settings_.shard_index, settings_.shard_count, settings_.output_dir.c_str(), runs_.size(),
           runs_.size() - todo_.size(), todo_.size(), study_.points.size(), settings_.mu.size(),
           settings_.sweep.empty() ? "" : (" x " + std::to_string(settings_.sweep.size()) + " swept keys").c_str(),
           settings_.phase_ensemble ? " + 64 phases" : "", settings_.realizations, model_.run.duration,
           model_.run.time_step, batch_threads(settings_), settings_.block_lanes);
  total_steps_ = static_cast<std::int64_t>(todo_.size()) * static_cast<std::int64_t>(steps);
  start_ = std::chrono::steady_clock::now();
  try {
    write_manifest(study_, settings_, runs_, todo_.empty());
  } catch (const std::exception& e) {  // e.g. the folder became unwritable since init()
    ROS_FATAL("gear_monte_carlo: %s", e.what());
    return 1;
  }

  BagSink sink(study_, settings_.output_dir);
  publish(sink, false);  // the totals at once, for rostopic echo
  std::thread monitor([&] { watch(sink); });
  std::string failure;
  try {
    run_batch(study_, todo_, settings_, sink, control_);
  } catch (const std::exception& e) {
    failure = e.what();
  }
  try {
    sink.finish();
  } catch (const std::exception& e) {
    if (failure.empty()) failure = e.what();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
  }
  wake_.notify_all();
  monitor.join();

  const bool complete = sink.bags_written() == todo_.size();
  try {
    write_manifest(study_, settings_, runs_, complete);
  } catch (const std::exception& e) {
    if (failure.empty()) failure = e.what();
  }
  publish(sink, true);
  const double wall = elapsed();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  ROS_INFO("gear_monte_carlo: %zu of %zu bags written in %.2f s wall (%.3g realization-steps/s; bag writer "
           "thread %.2f s CPU; peak RSS %.0f MB)%s",
           sink.bags_written(), todo_.size(), wall, static_cast<double>(control_.realization_steps) / wall,
           sink.writer_cpu_seconds(), static_cast<double>(usage.ru_maxrss) / 1024.0,
           complete ? "" : "; the rest stay to do: run the same batch again to resume");
  if (!failure.empty()) {
    ROS_FATAL("gear_monte_carlo: %s", failure.c_str());
    return 1;
  }
  if (complete) return 0;
  const int sig = stop_signal();  // read once: a second signal may arrive meanwhile
  return sig != 0 ? 128 + sig : 1;
}

double MonteCarloNode::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void MonteCarloNode::watch(const BagSink& sink) {
  constexpr double kLogPeriod = 5.0, kPublishPeriod = 1.0;
  double next_log = kLogPeriod, next_publish = kPublishPeriod;
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, std::chrono::milliseconds(100), [&] { return finished_; })) {
    if ((stop_signal() != 0 || !ros::ok()) && !control_.stop) {
      ROS_WARN("gear_monte_carlo: %s: abandoning the runs in flight, keeping the finished bags",
               stop_signal() != 0 ? stop_signal_name() : "ROS shutdown");
      control_.stop = true;
    }
    const double t = elapsed();
    if (t < next_publish) continue;
    next_publish += kPublishPeriod;
    const BatchProgress p = publish(sink, false);
    if (t < next_log) continue;
    next_log += kLogPeriod;
    ROS_INFO("gear_monte_carlo: %u/%u runs done (%u skipped), %.3g realization-steps/s, ETA %s",
             p.runs_done + p.runs_skipped, p.runs_total, p.runs_skipped, p.steps_per_second,
             clock_text(p.eta).c_str());
  }
}

BatchProgress MonteCarloNode::publish(const BagSink& sink, bool finished) {
  BatchProgress p;
  const ros::WallTime now = ros::WallTime::now();
  p.header.stamp = ros::Time(now.sec, now.nsec);
  p.output_dir = settings_.output_dir;
  p.shard_index = static_cast<std::uint32_t>(settings_.shard_index);
  p.shard_count = static_cast<std::uint32_t>(settings_.shard_count);
  p.runs_total = static_cast<std::uint32_t>(runs_.size());
  p.runs_skipped = static_cast<std::uint32_t>(runs_.size() - todo_.size());
  p.runs_done = static_cast<std::uint32_t>(sink.bags_written());
  p.realization_steps_done = static_cast<std::uint64_t>(control_.realization_steps.load());
  p.realization_steps_total = static_cast<std::uint64_t>(total_steps_);
  p.elapsed = elapsed();
  p.steps_per_second = p.elapsed > 0 ? static_cast<double>(p.realization_steps_done) / p.elapsed : 0.0;
  p.eta = p.steps_per_second > 0 && !finished
              ? static_cast<double>(p.realization_steps_total - p.realization_steps_done) / p.steps_per_second
              : (finished ? 0.0 : -1.0);
  p.finished = finished;
  progress_pub_.publish(p);
  return p;
}

}  // namespace gear_dynamics
