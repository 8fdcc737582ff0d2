#include "gear_dynamics/ros/aggregator_node.hpp"

#include <fcntl.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/this_node.h>
#include <spawn.h>
#include <xmlrpcpp/XmlRpcClient.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>

#include "gear_dynamics/analysis/over_time.hpp"
#include "gear_dynamics/analysis/study_analysis.hpp"
#include "gear_dynamics/report/report.hpp"
#include "gear_dynamics/report/series_csv.hpp"
#include "gear_dynamics/ros/batch_reader.hpp"
#include "gear_dynamics/ros/conversions.hpp"
#include "gear_dynamics/ros/report_message.hpp"
#include "gear_dynamics/ros/stop_signal.hpp"

extern char** environ;

namespace gear_dynamics {

AggregatorNode::AggregatorNode(const ros::NodeHandle& private_nh)
    : private_nh_(private_nh),
      settings_(parse_aggregator_settings(yaml_from_namespace(private_nh))),
      report_folder_(settings_.report_dir()) {
  publisher_ = private_nh_.advertise<BatchReport>("report", 1, /*latch=*/true);
}

bool AggregatorNode::run() {
  start_plot();
  if (settings_.wait_for_batch && !wait()) {
    plot(false);
    return false;
  }
  try {
    std::filesystem::create_directories(report_folder_);
    // read -> analyse -> report. The series are handed over as each bag is read, not kept: the
    // stochastic runs' reduced for the analyses over time (doc/gear_aggregator.md §8), the figures'
    // runs written to series.csv.
    SeriesDigests digests(settings_.analysis);
    FigureSeries figure_series(report_folder_, settings_.series_mu);
    ReadOptions options;
    options.wants_series = [&figure_series](const ManifestRun& run) {
      return run.kind == RunKind::Stochastic || figure_series.wants(run.kind, run.mu, run.realization);
    };
    options.on_series = [&](const BatchInputs& in, const RunRecord& run, const RunSeries& series) {
      if (run.kind == RunKind::Stochastic) digests.add(in, run, series.t, series.delta, series.delta_dot);
      if (figure_series.wants(run.kind, run.mu, run.index)) figure_series.add(run, series);
    };
    const BatchInputs inputs = read_batches(settings_.folders, options);
    StudyAnalysis study;  // per point and axis (doc/studies.md); the mu sweep's analysis is analyse()'s
    const BatchAnalysis analysis = analyse_batch(inputs, settings_.analysis, study);
    const BatchOverTime over_time = analyse_over_time(inputs, analysis, digests);
    for (const std::string& note : over_time.notes) ROS_WARN("gear_aggregator: %s", note.c_str());
    std::vector<std::string> written = write_report(report_folder_, inputs, analysis, &study, &over_time);
    written.push_back(figure_series.write(inputs.runs));
    ROS_INFO("gear_aggregator: %zu files written", written.size());
    plot(true);
    publisher_.publish(make_report_message(inputs, analysis, report_folder_));
  } catch (const std::exception& ex) {
    ROS_FATAL("gear_aggregator: %s", ex.what());
    plot(false);
    return false;
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);  // this process only: the bag readers are children
  ROS_INFO("gear_aggregator: report written to %s/report.md (peak RSS %.0f MB)", report_folder_.c_str(),
           static_cast<double>(usage.ru_maxrss) / 1024.0);
  return true;
}

namespace {

// Whether `node` is registered with the master and answers at its XML-RPC address (rosnode ping's
// test). The master alone keeps a node killed by SIGKILL or a crash listed for ever, and the
// aggregator would wait for it for ever.
bool node_alive(const std::string& node) {
  XmlRpc::XmlRpcValue args, response, uri;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, response, uri, false)) return false;
  std::string host;
  std::uint32_t port = 0;
  if (uri.getType() != XmlRpc::XmlRpcValue::TypeString || !ros::network::splitURI(uri, host, port)) return false;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue pid_args, pid;
  pid_args[0] = ros::this_node::getName();
  const bool answered = client.execute("getPid", pid_args, pid);
  client.close();
  return answered;
}

// A batch node that left its ~start_time at most this long before the wait began is this run's
// (a launch clears the node's namespace; an older value is an earlier run's, on a kept master).
constexpr double kStartSlack = 60.0;  // [s] of wall time

}  // namespace

bool AggregatorNode::wait() {
  const std::string& first = settings_.folders.front();
  ROS_INFO("gear_aggregator: waiting for the batch in %s", first.c_str());
  const ros::WallTime start = ros::WallTime::now();
  bool seen = false;
  const std::string start_key = settings_.batch_node + "/start_time";
  // Whether every listed bag is there is asked again when a manifest was rewritten (a writer does
  // that after its last bag) and every 10 s besides: parsing the manifest of a large batch at every
  // poll would take CPU from the batch it waits for.
  constexpr double kPollPeriod = 0.2, kRecheckPeriod = 10.0;
  std::string checked;  // the manifests' signatures at the last check
  ros::WallTime last_check;  // 0: the first poll checks
  while (ros::ok()) {
    std::string signatures;
    for (const std::string& f : settings_.folders) signatures += manifests_signature(f) + '\n';
    const ros::WallTime now = ros::WallTime::now();
    if (signatures != checked || (now - last_check).toSec() >= kRecheckPeriod) {
      checked = signatures;
      last_check = now;
      bool complete = true;
      for (const std::string& f : settings_.folders) complete = complete && batch_complete(f);
      if (complete) return true;
    }
    const bool running = node_alive(settings_.batch_node);
    // A batch node that ended before the first poll (a folder refused at once, or killed while this
    // node was still starting under load) is never seen alive: its start time tells that it ran.
    double started = 0.0;
    if (running || (ros::param::get(start_key, started) && started >= start.toSec() - kStartSlack)) seen = true;
    if (seen && !running) {
      ROS_WARN("gear_aggregator: %s ended before its batch was complete; aggregating what it left",
               settings_.batch_node.c_str());
      return true;
    }
    if (settings_.wait_timeout > 0 && (ros::WallTime::now() - start).toSec() > settings_.wait_timeout) {
      ROS_FATAL("gear_aggregator: the batch in %s is not complete after ~wait_timeout = %g s", first.c_str(),
                settings_.wait_timeout);
      return false;
    }
    ros::WallDuration(kPollPeriod).sleep();
  }
  warn_at_stop("gear_aggregator: shut down while waiting for the batch in " + first + "; no report");
  return false;
}

void AggregatorNode::start_plot() {
  if (settings_.plot_script.empty()) return;
  std::vector<std::string> args{"/usr/bin/python3", settings_.plot_script, report_folder_, "--wait"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int go[2];
  if (pipe2(go, O_CLOEXEC) != 0) return;  // then plot() draws nothing and says so
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, go[0], STDIN_FILENO);  // dup2 clears O_CLOEXEC on stdin
  if (posix_spawn(&plot_pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) plot_pid_ = -1;
  posix_spawn_file_actions_destroy(&actions);
  close(go[0]);
  plot_go_ = go[1];
  signal(SIGPIPE, SIG_IGN);  // a script that died early must not end this node at the write (roscpp ignores it too)
}

void AggregatorNode::plot(bool draw) {
  if (plot_go_ < 0) {
    if (draw && !settings_.plot_script.empty())
      ROS_WARN("gear_aggregator: %s could not be started; the report and CSV files are complete",
               settings_.plot_script.c_str());
    return;
  }
  const bool told = !draw || write(plot_go_, "draw\n", 5) == 5;
  close(plot_go_);
  plot_go_ = -1;
  int status = 0;
  const bool ended = plot_pid_ > 0 && waitpid(plot_pid_, &status, 0) == plot_pid_;
  plot_pid_ = -1;
  if (draw && (!told || !ended || !WIFEXITED(status) || WEXITSTATUS(status) != 0))
    ROS_WARN("gear_aggregator: %s did not draw the figures (exit status %d); the report and CSV files are complete",
             settings_.plot_script.c_str(), ended && WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

}  // namespace gear_dynamics
