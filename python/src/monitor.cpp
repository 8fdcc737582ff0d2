// The monitor layer (monitor/indicators.hpp, monitor/reference.hpp) and the bifurcation scan
// (dynamics/bifurcation.hpp) seen from Python: the core's functions on numpy arrays, no tool between.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "gear_dynamics/dynamics/bifurcation.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/monitor/indicators.hpp"
#include "gear_dynamics/monitor/reference.hpp"
#include "module.hpp"

namespace py = pybind11;

namespace gear_dynamics::python {
namespace {

py::array_t<double> array(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}
py::array_t<double> array(const Eigen::VectorXd& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

using Samples = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The signal, its angle and its load as equal-length 1-D arrays (load: zeros if None).
struct Series {
  Samples value, angle, load;
  py::ssize_t n = 0;
};
Series series(const Samples& value, const Samples& angle, const std::optional<Samples>& load) {
  Series s{value, angle, load ? *load : Samples(value.size()), value.size()};
  if (!load) std::fill(s.load.mutable_data(), s.load.mutable_data() + s.n, 0.0);
  if (value.ndim() != 1 || angle.ndim() != 1 || s.load.ndim() != 1)
    throw std::invalid_argument("signal, shaft_angle and load must be 1-D arrays");
  if (angle.size() != s.n || s.load.size() != s.n)
    throw std::invalid_argument("signal (" + std::to_string(s.n) + " samples), shaft_angle (" +
                                std::to_string(angle.size()) + ") and load (" + std::to_string(s.load.size()) +
                                ") must have the same length");
  return s;
}

// Columns per window: every indicator of indicator_table() and the window's place.
struct WindowColumns {
  std::vector<std::vector<double>> indicators = std::vector<std::vector<double>>(indicator_table().size());
  std::vector<double> start_angle, mean_load, index;
  void add(const RevolutionWindow& w, const std::vector<double>& values) {
    for (std::size_t k = 0; k < values.size(); ++k) indicators[k].push_back(values[k]);
    start_angle.push_back(w.start_angle);
    mean_load.push_back(w.mean_load);
    index.push_back(static_cast<double>(w.index));
  }
  py::dict dict() const {
    py::dict out;
    for (std::size_t k = 0; k < indicators.size(); ++k) out[indicator_table()[k].name] = array(indicators[k]);
    out["start_angle"] = array(start_angle);
    out["mean_load"] = array(mean_load);
    out["window"] = array(index);
    return out;
  }
};

IndicatorSettings settings_of(int teeth, int samples_per_revolution, int shaft_orders, int sideband_orders,
                              int envelope_band) {
  IndicatorSettings s;
  s.teeth = teeth;
  s.samples_per_revolution = samples_per_revolution;
  s.shaft_orders = shaft_orders;
  s.sideband_orders = sideband_orders;
  s.envelope_band = envelope_band;
  validate(s);
  return s;
}

py::dict indicators(const Samples& value, const Samples& angle, std::optional<Samples> load, int teeth,
                    double revolution, int revolutions, int samples_per_revolution, int shaft_orders,
                    int sideband_orders, int envelope_band, double baseline_residual_variance) {
  const Series s = series(value, angle, load);
  const IndicatorSettings settings = settings_of(teeth, samples_per_revolution, shaft_orders, sideband_orders, envelope_band);
  if (!(revolution > 0)) throw std::invalid_argument("revolution_angle = " + std::to_string(revolution) + " rad: must be > 0");
  if (revolutions < 1) throw std::invalid_argument("revolutions = " + std::to_string(revolutions) + ": must be >= 1");
  WindowColumns columns;
  std::int64_t restarts = 0;
  {
    py::gil_scoped_release release;
    RevolutionWindows windows(revolution, revolutions, samples_per_revolution);
    IndicatorTracker tracker(settings, baseline_residual_variance);
    const double *v = s.value.data(), *a = s.angle.data(), *l = s.load.data();
    for (py::ssize_t i = 0; i < s.n; ++i)
      if (const auto w = windows.add(a[i], v[i], l[i])) columns.add(*w, tracker.window(w->tsa));
    restarts = windows.restarts();
  }
  py::dict out = columns.dict();
  out["restarts"] = restarts;
  return out;
}

py::dict decompose_tsa(const Samples& tsa, int teeth, int shaft_orders, int sideband_orders, int envelope_band) {
  if (tsa.ndim() != 1) throw std::invalid_argument("tsa must be a 1-D array");
  const IndicatorSettings settings =
      settings_of(teeth, static_cast<int>(tsa.size()), shaft_orders, sideband_orders, envelope_band);
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(tsa.data(), tsa.size());
  const GearSignals g = decompose(x, settings);
  py::dict out;
  out["tsa"] = array(g.tsa);
  out["regular"] = array(g.regular);
  out["residual"] = array(g.residual);
  out["difference"] = array(g.difference);
  out["envelope"] = array(g.envelope);
  out["amplitude"] = array(g.amplitude);
  out["mesh_order"] = g.mesh_order;
  return out;
}

py::list indicator_list() {
  py::list out;
  for (const IndicatorSpec& s : indicator_table()) {
    py::dict d;
    d["name"] = s.name;
    d["unit"] = s.unit;
    d["description"] = s.description;
    out.append(d);
  }
  return out;
}

py::dict reference_summary(const Reference& r) {
  py::list bands;
  for (const ReferenceBand& b : r.bands) {
    py::dict d;
    d["load"] = b.load;
    d["load_low"] = b.load_low;
    d["load_high"] = b.load_high;
    d["windows"] = b.windows;
    d["mean"] = array(b.mean);
    d["sd"] = array(b.sd);
    d["threshold"] = array(b.threshold);
    d["t2_threshold"] = b.t2_threshold;
    d["baseline_residual_variance"] = b.baseline_residual_variance;
    bands.append(d);
  }
  const MonitorSettings& m = r.settings.monitor;
  py::dict monitor;
  monitor["signal"] = to_string(m.signal);
  monitor["revolutions_per_window"] = m.revolutions_per_window;
  monitor["samples_per_revolution"] = m.samples_per_revolution;
  monitor["decimation"] = m.decimation;
  py::dict out;
  out["package_version"] = r.package_version;
  out["indicators"] = r.indicators;
  out["cusum_threshold"] = r.cusum_threshold;
  out["false_alarm"] = r.settings.false_alarm;
  out["monitor"] = monitor;
  out["bands"] = bands;
  return out;
}

py::dict read_reference_file(const std::string& path) { return reference_summary(read_reference(path)); }

// The windows of a signal against a healthy reference file: the monitor of gear_monitor's node,
// window by window (indicators with the run's trends, T², its score, the CUSUM, the health).
py::dict assess(const Samples& value, const Samples& angle, std::optional<Samples> load, const std::string& path,
                const std::vector<std::string>& files, const std::vector<std::string>& sets) {
  const Series s = series(value, angle, load);
  Reference reference = read_reference(path);
  if (!files.empty() || !sets.empty())
    check_reference(reference, parse_config(model_root(files, sets, std::nullopt, std::nullopt)), path);
  WindowColumns columns;
  std::vector<double> t2, score, cusum, band, t2_alarm, cusum_alarm;
  std::vector<std::string> health;
  {
    py::gil_scoped_release release;
    ConditionMonitor monitor(std::move(reference));
    const MonitorSettings& m = monitor.settings();
    RevolutionWindows windows(monitor.revolution_angle(), m.revolutions_per_window, m.samples_per_revolution);
    const double *v = s.value.data(), *a = s.angle.data(), *l = s.load.data();
    for (py::ssize_t i = 0; i < s.n; ++i) {
      const auto w = windows.add(a[i], v[i], l[i]);
      if (!w) continue;
      const Assessment x = monitor.assess(*w);
      columns.add(*w, x.indicators);
      t2.push_back(x.t2);
      score.push_back(x.score);
      cusum.push_back(x.cusum);
      band.push_back(static_cast<double>(x.band));
      t2_alarm.push_back(x.t2_alarm ? 1.0 : 0.0);
      cusum_alarm.push_back(x.cusum_alarm ? 1.0 : 0.0);
      health.emplace_back(to_string(x.health));
    }
  }
  py::dict out = columns.dict();
  out["t2"] = array(t2);
  out["score"] = array(score);
  out["cusum"] = array(cusum);
  out["band"] = array(band);
  out["t2_alarm"] = array(t2_alarm);
  out["cusum_alarm"] = array(cusum_alarm);
  out["health"] = health;
  return out;
}

py::list bifurcation(const std::vector<std::string>& files, const std::vector<std::string>& sets, std::optional<double> mu,
                     const std::string& parameter, const std::vector<double>& values, double duration, double transient,
                     int block_lanes, int max_period, double tolerance) {
  const ModelConfig c = parse_config(model_root(files, sets, mu, std::nullopt));
  const ScanParameter p = parse_scan_parameter(parameter);
  if (values.empty()) throw std::invalid_argument("values: give at least one value of " + parameter);
  if (!(duration > 0)) throw std::invalid_argument("duration = " + std::to_string(duration) + " s: must be > 0");
  if (!(transient >= 0 && transient < duration))
    throw std::invalid_argument("transient = " + std::to_string(transient) + " s is out of range; allowed [0, duration = " +
                                std::to_string(duration) + ") s");
  if (block_lanes < 1) throw std::invalid_argument("block_lanes = " + std::to_string(block_lanes) + ": must be >= 1");
  if (max_period < 1) throw std::invalid_argument("max_period = " + std::to_string(max_period) + ": must be >= 1");
  if (!(tolerance > 0)) throw std::invalid_argument("tolerance = " + std::to_string(tolerance) + ": must be > 0");
  ScanOptions o;
  o.duration = duration;
  o.transient = transient;
  o.block_lanes = block_lanes;
  o.max_period = max_period;
  o.tolerance = tolerance;
  std::vector<ScanValue> r;
  {
    py::gil_scoped_release release;
    r = bifurcation_scan(c, p, values, o);
  }
  py::list out;
  for (const ScanValue& v : r) {
    std::vector<double> t, d, dv;
    for (const SectionState& q : v.points) {
      t.push_back(q.time);
      d.push_back(q.x[0]);
      dv.push_back(q.x[1]);
    }
    py::dict e;
    e["value"] = v.value;
    e["period"] = v.period;
    e["regime"] = v.regime;
    e["min_gap"] = v.min_gap;
    e["min_delta"] = v.min_delta;
    e["t"] = array(t);
    e["delta"] = array(d);
    e["delta_dot"] = array(dv);
    out.append(e);
  }
  return out;
}

}  // namespace

void bind_monitor(py::module_& m) {
  py::register_exception<ReferenceError>(m, "ReferenceError", PyExc_OSError).doc() =
      "A monitor reference file that cannot be read or does not fit the gear: the text names the file and the reason.";
  m.def("indicators", &indicators, py::arg("signal"), py::arg("shaft_angle"), py::arg("load"), py::arg("teeth"),
        py::arg("revolution_angle"), py::arg("revolutions"), py::arg("samples_per_revolution"), py::arg("shaft_orders"),
        py::arg("sideband_orders"), py::arg("envelope_band"), py::arg("baseline_residual_variance"),
        "Condition indicators per window of whole revolutions.");
  m.def("decompose", &decompose_tsa, py::arg("tsa"), py::arg("teeth"), py::arg("shaft_orders"),
        py::arg("sideband_orders"), py::arg("envelope_band"), "A TSA's regular, residual, difference and envelope signals.");
  m.def("indicator_table", &indicator_list, "The indicators: name, unit, description.");
  m.def("read_reference", &read_reference_file, py::arg("path"), "A monitor reference file's bands and thresholds.");
  m.def("assess", &assess, py::arg("signal"), py::arg("shaft_angle"), py::arg("load"), py::arg("path"),
        py::arg("files"), py::arg("sets"), "Windows of a signal assessed against a reference file.");
  m.def("bifurcation", &bifurcation, py::arg("files"), py::arg("sets"), py::arg("mu"), py::arg("parameter"),
        py::arg("values"), py::arg("duration"), py::arg("transient"), py::arg("block_lanes"), py::arg("max_period"),
        py::arg("tolerance"), "A bifurcation scan of S1 over one parameter.");
}

}  // namespace gear_dynamics::python
