// gear_aggregator: reads Monte Carlo batch folders, computes the paper's statistics with their
// uncertainty (core: batch_analysis, report), writes the report folder, draws the figures and
// latches a BatchReport on ~report. A thin wrapper: every number comes from the core library.
#include <ros/master.h>
#include <ros/ros.h>
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>

#include "gear_dynamics/analysis/study_analysis.hpp"
#include "gear_dynamics/ros/batch_reader.hpp"
#include "gear_dynamics/ros/conversions.hpp"
#include "gear_dynamics/ros/report_message.hpp"

extern char** environ;

namespace gear_dynamics {

class Aggregator {
 public:
  // Reads the parameters; success = false (after ROS_FATAL) if they are unusable.
  Aggregator(ros::NodeHandle& pnh, bool& success) : pnh_(pnh) {
    success = false;
    XmlRpc::XmlRpcValue folders;
    if (pnh.getParam("folders", folders) && folders.getType() == XmlRpc::XmlRpcValue::TypeString) {
      folders_.push_back(static_cast<std::string>(folders));
    } else if (folders.valid() && folders.getType() == XmlRpc::XmlRpcValue::TypeArray) {
      for (int i = 0; i < folders.size(); ++i)
        if (folders[i].getType() == XmlRpc::XmlRpcValue::TypeString) folders_.push_back(static_cast<std::string>(folders[i]));
    }
    if (folders_.empty() || (folders.getType() == XmlRpc::XmlRpcValue::TypeArray && static_cast<int>(folders_.size()) != folders.size())) {
      ROS_FATAL("~folders must be a batch folder path or a list of them (strings); got %s",
                folders.valid() ? folders.toXml().c_str() : "nothing");
      return;
    }
    report_folder_ = pnh.param<std::string>("report_folder", "");
    if (report_folder_.empty()) report_folder_ = (std::filesystem::path(folders_.front()) / "report").string();
    wait_for_batch_ = pnh.param("wait_for_batch", false);
    batch_node_ = pnh.param<std::string>("batch_node", "/gear_monte_carlo");
    wait_timeout_ = pnh.param("wait_timeout", 0.0);
    plot_script_ = pnh.param<std::string>("plot_script", "");
    series_mu_ = pnh.param("series_mu", 0.04);
    if (wait_timeout_ < 0) {
      ROS_FATAL("~wait_timeout = %g s is out of range; allowed >= 0 s (0 = no limit)", wait_timeout_);
      return;
    }
    try {
      settings_ = parse_analysis_settings(yaml_from_parameters(pnh, {"analysis"}));
    } catch (const std::exception& ex) {
      ROS_FATAL("%s", ex.what());
      return;
    }
    publisher_ = pnh.advertise<BatchReport>("report", 1, /*latch=*/true);
    success = true;
  }

  // Waits for the batch if asked, then reads, analyses, writes and publishes. False on failure.
  bool run() {
    if (wait_for_batch_ && !wait()) return false;
    try {
      std::filesystem::create_directories(report_folder_);
      ReadOptions options;
      options.series_csv = (std::filesystem::path(report_folder_) / "series.csv").string();
      options.series_mu = series_mu_;
      const BatchInputs inputs = read_batches(folders_, options);
      StudyAnalysis study;  // per point and axis (doc/studies.md); the mu sweep's analysis is analyse()'s
      const BatchAnalysis analysis = analyse_batch(inputs, settings_, study);
      write_report(report_folder_, inputs, analysis, &study);
      plot();
      publisher_.publish(make_report_message(inputs, analysis, report_folder_));
    } catch (const std::exception& ex) {
      ROS_FATAL("gear_aggregator: %s", ex.what());
      return false;
    }
    ROS_INFO("gear_aggregator: report written to %s/report.md", report_folder_.c_str());
    return true;
  }

 private:
  // Until every folder's manifest lists only finished bags, or the batch node has come and gone
  // (it failed or was stopped: what it left is aggregated, the rest reported missing).
  bool wait() {
    ROS_INFO("gear_aggregator: waiting for the batch in %s", folders_.front().c_str());
    const ros::WallTime start = ros::WallTime::now();
    bool seen = false;
    while (ros::ok()) {
      bool complete = true;
      for (const std::string& f : folders_) complete = complete && batch_complete(f);
      if (complete) return true;
      std::vector<std::string> nodes;
      const bool running = ros::master::getNodes(nodes) &&
                           std::find(nodes.begin(), nodes.end(), batch_node_) != nodes.end();
      if (running) seen = true;
      if (seen && !running) {
        ROS_WARN("gear_aggregator: %s ended before its batch was complete; aggregating what it left", batch_node_.c_str());
        return true;
      }
      if (wait_timeout_ > 0 && (ros::WallTime::now() - start).toSec() > wait_timeout_) {
        ROS_FATAL("gear_aggregator: the batch in %s is not complete after ~wait_timeout = %g s", folders_.front().c_str(),
                  wait_timeout_);
        return false;
      }
      ros::WallDuration(0.5).sleep();
    }
    return false;
  }

  // Figures from the CSV files (scripts/plot_report.py); a failure costs the figures, not the report.
  void plot() const {
    if (plot_script_.empty()) return;
    std::vector<std::string> args{"/usr/bin/python3", plot_script_, report_folder_};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid;
    int status = 0;
    if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0 || waitpid(pid, &status, 0) < 0 ||
        !WIFEXITED(status) || WEXITSTATUS(status) != 0)
      ROS_WARN("gear_aggregator: %s did not draw the figures (exit status %d); the report and CSV files are complete",
               plot_script_.c_str(), WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  }

  ros::NodeHandle pnh_;
  std::vector<std::string> folders_;
  std::string report_folder_, batch_node_, plot_script_;
  bool wait_for_batch_ = false;
  double wait_timeout_ = 0, series_mu_ = 0.04;
  AnalysisSettings settings_;
  ros::Publisher publisher_;
};

}  // namespace gear_dynamics

int main(int argc, char** argv) {
  ros::init(argc, argv, "gear_aggregator");
  ros::NodeHandle pnh("~");
  bool ok = false;
  gear_dynamics::Aggregator aggregator(pnh, ok);
  if (!ok || !aggregator.run()) return 1;
  if (!pnh.param("exit_when_done", false)) ros::spin();
  return 0;
}
