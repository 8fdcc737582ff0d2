// The package's C++ side of test/foxglove: what it reads from bags, as JSON for read_bags.js.
//   cpp_reference bag FILE.bag     every GearState, RunInfo, RunSummary and PoincarePoint of the bag, through
//                                  rosbag::View and the package's generated C++ message classes
//   cpp_reference batch FOLDER CSV OUT.json
//                                  the package's own batch reader (read_batches, behind
//                                  gear_aggregator): one record per run into OUT.json (its log
//                                  goes to stdout), the S1/S2/S3 series at mu = 0.04 to CSV
// Integers are written as strings (uint64 does not fit a JavaScript number), doubles with 17
// significant digits (they read back exactly), non-finite doubles as "nan", "inf", "-inf".
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/PoincarePoint.h"
#include "gear_dynamics/RunInfo.h"
#include "gear_dynamics/RunSummary.h"
#include "gear_dynamics/report/report.hpp"
#include "gear_dynamics/report/series_csv.hpp"
#include "gear_dynamics/ros/batch_reader.hpp"

namespace gd = gear_dynamics;

namespace {

std::string num(double v) {
  if (std::isnan(v)) return "\"nan\"";
  if (std::isinf(v)) return v > 0 ? "\"inf\"" : "\"-inf\"";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

template <class T>
std::string integer(T v) {
  return "\"" + std::to_string(v) + "\"";
}

std::string str(const std::string& s) {
  std::ostringstream o;
  o << '"';
  for (const unsigned char c : s) {
    if (c == '"' || c == '\\') {
      o << '\\' << c;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o << buf;
    } else {
      o << c;
    }
  }
  o << '"';
  return o.str();
}

std::string nums(const std::vector<double>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? "," : "") + num(v[i]);
  return out + "]";
}

// The JSON object of the fields, in message order.
class Obj {
 public:
  Obj& add(const std::string& key, const std::string& json) {
    text_ += (text_.empty() ? "{" : ",") + str(key) + ":" + json;
    return *this;
  }
  std::string done() const { return text_.empty() ? "{}" : text_ + "}"; }

 private:
  std::string text_;
};

std::string header(const std_msgs::Header& h) {
  return Obj()
      .add("seq", integer(h.seq))
      .add("stamp", Obj().add("sec", integer(h.stamp.sec)).add("nsec", integer(h.stamp.nsec)).done())
      .add("frame_id", str(h.frame_id))
      .done();
}

std::string fields(const gd::GearState& m) {
  return Obj()
      .add("header", header(m.header))
      .add("t", num(m.t))
      .add("delta", num(m.delta))
      .add("delta_dot", num(m.delta_dot))
      .add("phi", num(m.phi))
      .add("center_distance", num(m.center_distance))
      .add("mesh_stiffness", num(m.mesh_stiffness))
      .add("mesh_phase", num(m.mesh_phase))
      .add("mu", num(m.mu))
      .add("sigma", num(m.sigma))
      .add("realization", integer(m.realization))
      .add("seed", integer(m.seed))
      .done();
}

std::string fields(const gd::RunInfo& m) {
  return Obj()
      .add("header", header(m.header))
      .add("package_version", str(m.package_version))
      .add("kind", str(m.kind))
      .add("seed", integer(m.seed))
      .add("realization", integer(m.realization))
      .add("mu", num(m.mu))
      .add("sigma", num(m.sigma))
      .add("time_step", num(m.time_step))
      .add("duration", num(m.duration))
      .add("mesh_phase", num(m.mesh_phase))
      .add("clock_offset", num(m.clock_offset))
      .add("parameters_yaml", str(m.parameters_yaml))
      .done();
}

std::string fields(const gd::RunSummary& m) {
  return Obj()
      .add("header", header(m.header))
      .add("run_name", str(m.run_name))
      .add("kind", str(m.kind))
      .add("realization", integer(m.realization))
      .add("mu", num(m.mu))
      .add("mesh_phase", num(m.mesh_phase))
      .add("center_distance", num(m.center_distance))
      .add("delta_range", num(m.delta_range))
      .add("delta_dot_range", num(m.delta_dot_range))
      .add("steady_state_time", num(m.steady_state_time))
      .add("steady_state_time_fine", num(m.steady_state_time_fine))
      .add("reached_steady_state", m.reached_steady_state ? "true" : "false")
      .add("final_delta", num(m.final_delta))
      .add("final_delta_dot", num(m.final_delta_dot))
      .add("final_phi", num(m.final_phi))
      .add("snapshot_times", nums(m.snapshot_times))
      .add("snapshot_delta", nums(m.snapshot_delta))
      .add("snapshot_delta_dot", nums(m.snapshot_delta_dot))
      .add("snapshot_phi", nums(m.snapshot_phi))
      .done();
}

std::string fields(const gd::PoincarePoint& m) {
  return Obj()
      .add("t", num(m.t))
      .add("delta", num(m.delta))
      .add("delta_dot", num(m.delta_dot))
      .add("mesh_phase", num(m.mesh_phase))
      .done();
}

// {"messages": [{"topic", "type", "time", "fields"}, ...]} of the four types, in bag order (time:
// the receive time of the bag record).
int dump_bag(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::cout << "{\"messages\":[";
  bool first = true;
  for (const rosbag::MessageInstance& m : view) {
    std::string json;
    if (const auto s = m.instantiate<gd::GearState>()) {
      json = fields(*s);
    } else if (const auto i = m.instantiate<gd::RunInfo>()) {
      json = fields(*i);
    } else if (const auto r = m.instantiate<gd::RunSummary>()) {
      json = fields(*r);
    } else if (const auto p = m.instantiate<gd::PoincarePoint>()) {
      json = fields(*p);
    } else {
      continue;
    }
    const ros::Time t = m.getTime();
    std::cout << (first ? "" : ",")
              << Obj()
                     .add("topic", str(m.getTopic()))
                     .add("type", str(m.getDataType()))
                     .add("time", Obj().add("sec", integer(t.sec)).add("nsec", integer(t.nsec)).done())
                     .add("fields", json)
                     .done()
              << '\n';
    first = false;
  }
  std::cout << "]}\n";
  return 0;
}

int dump_batch(const std::string& folder, const std::string& csv, const std::string& json) {
  const double series_mu = 0.04;
  const std::string csv_folder = std::filesystem::path(csv).parent_path().string();
  gd::FigureSeries figure_series(csv_folder.empty() ? "." : csv_folder, series_mu);
  gd::ReadOptions options;
  options.wants_series = [&](const gd::ManifestRun& run) { return figure_series.wants(run.kind, run.mu, run.realization); };
  options.on_series = [&](const gd::BatchInputs&, const gd::RunRecord& run, const gd::RunSeries& series) {
    figure_series.add(run, series);
  };
  const gd::BatchInputs in = gd::read_batches({folder}, options);
  const std::string written = figure_series.write(in.runs);
  if (written != csv) std::filesystem::rename(written, csv);
  std::ofstream out(json);
  out << "{\"to_paper_units\":" << num(gd::kToPaperUnits) << ",\"series_mu\":" << num(series_mu)
            << ",\"skipped\":" << in.skipped.size() << ",\"missing\":" << in.missing.size() << ",\"runs\":[";
  for (std::size_t i = 0; i < in.runs.size(); ++i) {
    const gd::RunRecord& r = in.runs[i];
    out << (i ? "," : "")
        << Obj()
                     .add("name", str(r.name))
                     .add("kind", str(gd::to_string(r.kind)))
                     .add("mu", num(r.mu))
                     .add("index", integer(r.index))
                     .add("center_distance", num(r.center_distance))
                     .add("steady_state_time", num(r.steady_state_time))
                     .add("steady_state_time_fine", num(r.steady_state_time_fine))
                     .add("reached_steady_state", r.reached_steady_state ? "true" : "false")
                     .add("final_delta", num(r.final_delta))
                     .add("final_delta_dot", num(r.final_delta_dot))
                     .add("final_phi", num(r.final_phi))
                     .add("snapshot_times", nums(r.snapshot_times))
                     .add("snapshot_delta", nums(r.snapshot_delta))
                     .add("snapshot_delta_dot", nums(r.snapshot_delta_dot))
                     .done()
        << '\n';
  }
  out << "]}\n";
  return out.good() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() == 2 && args[0] == "bag") return dump_bag(args[1]);
    if (args.size() == 4 && args[0] == "batch") return dump_batch(args[1], args[2], args[3]);
  } catch (const std::exception& e) {
    std::cerr << "cpp_reference: " << e.what() << '\n';
    return 1;
  }
  std::cerr << "usage: cpp_reference bag FILE.bag | cpp_reference batch FOLDER SERIES.csv OUT.json\n";
  return 2;
}
