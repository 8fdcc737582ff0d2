// gear_dynamics._batch: batch folders read through the package's own reader (ros/batch_reader.hpp),
// with the manifest's checks and refusals. Apart from _core so that simulate needs no ROS library.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "gear_dynamics/batch/run_kind.hpp"
#include "gear_dynamics/ros/batch_reader.hpp"

namespace py = pybind11;
namespace gd = gear_dynamics;

namespace {

template <class F>
py::array_t<double> column(const std::vector<gd::RunRecord>& runs, F get) {
  py::array_t<double> a(static_cast<py::ssize_t>(runs.size()));
  auto m = a.mutable_unchecked<1>();
  for (std::size_t i = 0; i < runs.size(); ++i) m(static_cast<py::ssize_t>(i)) = get(runs[i]);
  return a;
}

py::dict read_batch(const std::vector<std::string>& folders, bool all_series, const std::vector<std::string>& series) {
  const std::set<std::string> wanted(series.begin(), series.end());
  std::map<std::string, gd::RunSeries> kept;
  std::mutex lock;
  gd::ReadOptions options;
  if (all_series || !wanted.empty()) {
    options.wants_series = [&](const gd::ManifestRun& r) { return all_series || wanted.count(r.name) > 0; };
    options.on_series = [&](const gd::BatchInputs&, const gd::RunRecord& r, const gd::RunSeries& s) {
      std::lock_guard<std::mutex> g(lock);
      kept[r.name] = s;
    };
  }
  gd::BatchInputs in;
  {
    py::gil_scoped_release release;
    in = gd::read_batches(folders, options);
  }
  const auto& runs = in.runs;
  py::dict cols;
  std::vector<std::string> names, kinds;
  for (const auto& r : runs) {
    names.push_back(r.name);
    kinds.push_back(gd::to_string(r.kind));
  }
  cols["name"] = names;
  cols["kind"] = kinds;
  cols["mu"] = column(runs, [](const gd::RunRecord& r) { return r.mu; });
  cols["index"] = column(runs, [](const gd::RunRecord& r) { return double(r.index); });
  cols["point"] = column(runs, [](const gd::RunRecord& r) { return double(r.point); });
  cols["center_distance"] = column(runs, [](const gd::RunRecord& r) { return r.center_distance; });
  cols["steady_state_time"] = column(runs, [](const gd::RunRecord& r) { return r.steady_state_time; });
  cols["steady_state_time_fine"] = column(runs, [](const gd::RunRecord& r) { return r.steady_state_time_fine; });
  cols["reached_steady_state"] =
      column(runs, [](const gd::RunRecord& r) { return r.reached_steady_state ? 1.0 : 0.0; });
  cols["final_delta"] = column(runs, [](const gd::RunRecord& r) { return r.final_delta; });
  cols["final_delta_dot"] = column(runs, [](const gd::RunRecord& r) { return r.final_delta_dot; });
  cols["final_phi"] = column(runs, [](const gd::RunRecord& r) { return r.final_phi; });
  // Snapshots: (runs, times) when every run has the same times (one batch), as the manifest asks.
  const std::size_t ns = runs.empty() ? 0 : runs[0].snapshot_times.size();
  py::array_t<double> st(static_cast<py::ssize_t>(ns)), sd({static_cast<py::ssize_t>(runs.size()), static_cast<py::ssize_t>(ns)}),
      sv({static_cast<py::ssize_t>(runs.size()), static_cast<py::ssize_t>(ns)});
  auto mst = st.mutable_unchecked<1>();
  auto msd = sd.mutable_unchecked<2>();
  auto msv = sv.mutable_unchecked<2>();
  for (std::size_t j = 0; j < ns; ++j) mst(static_cast<py::ssize_t>(j)) = runs[0].snapshot_times[j];
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].snapshot_times.size() != ns) throw std::runtime_error("runs with different snapshot times");
    for (std::size_t j = 0; j < ns; ++j) {
      msd(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(j)) = runs[i].snapshot_delta[j];
      msv(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(j)) = runs[i].snapshot_delta_dot[j];
    }
  }
  py::dict out;
  out["runs"] = cols;
  out["snapshot_times"] = st;
  out["snapshot_delta"] = sd;
  out["snapshot_delta_dot"] = sv;
  py::dict series_out;
  for (const auto& [name, s] : kept) {
    py::dict d;
    d["t"] = py::array_t<double>(static_cast<py::ssize_t>(s.t.size()), s.t.data());
    d["delta"] = py::array_t<double>(static_cast<py::ssize_t>(s.delta.size()), s.delta.data());
    d["delta_dot"] = py::array_t<double>(static_cast<py::ssize_t>(s.delta_dot.size()), s.delta_dot.data());
    d["phi"] = py::array_t<double>(static_cast<py::ssize_t>(s.phi.size()), s.phi.data());
    series_out[py::str(name)] = d;
  }
  out["series"] = series_out;
  out["folders"] = in.folders;
  out["expected_runs"] = in.expected_runs;
  std::vector<std::pair<std::string, std::string>> skipped;
  for (const auto& s : in.skipped) skipped.emplace_back(s.file, s.reason);
  out["skipped"] = skipped;
  out["missing"] = in.missing;
  std::vector<std::string> axes;
  for (const auto& a : in.axes) axes.push_back(a.key);
  out["axes"] = axes;
  out["points"] = in.points;
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << gd::to_yaml(in.config);
  out["config_text"] = std::string(e.c_str());
  return out;
}

}  // namespace

PYBIND11_MODULE(_batch, m) {
  m.doc() = "Batch folders through the package's reader (use gear_dynamics.read_batch).";
  py::register_exception<gd::BatchReadError>(m, "BatchReadError", PyExc_OSError).doc() =
      "The batch cannot be read: no folder, no manifest, manifests of different batches, no usable bag.";
  m.def("read_batch", &read_batch, py::arg("folders"), py::arg("all_series"), py::arg("series"),
        "The runs of batch folders as columns of numpy arrays.");
}
