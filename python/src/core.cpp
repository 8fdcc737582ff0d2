// gear_dynamics._core: the ROS-free core seen from Python. The configuration is gear_run's (the same
// defaults, overlays and --set overrides, the same ConfigError text); simulate() runs the same
// Ensemble and Recorder as gear_run, so its arrays hold gear_run's numbers bit for bit.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/simulation.hpp"
#include "gear_dynamics/dynamics/lyapunov.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"
#include "gear_dynamics/dynamics/system.hpp"
#include "gear_dynamics/maths/spectrum.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/tooth_stiffness.hpp"
#include "gear_dynamics/monitor/reference.hpp"
#include "gear_dynamics/config/model_files.hpp"
#include "module.hpp"

namespace py = pybind11;
namespace gd = gear_dynamics;

namespace {

// Thrown out of the engine's observer when Python has a pending exception (Ctrl-C): unwinds the
// run, then the exception is restored with the GIL held.
struct PythonInterrupt {};

}  // namespace

YAML::Node gd::python::model_root(const std::vector<std::string>& files, const std::vector<std::string>& sets,
                                  std::optional<double> mu, std::optional<long long> seed) {
  gd::ModelOptions o;
  o.files = files;
  o.sets = sets;
  o.mu = mu;
  YAML::Node root = gd::model_yaml(o);
  if (seed) root["run"]["seed"] = *seed;
  // gear_run's notice of snapshot times after run.duration, as a Python warning.
  if (const std::string notice = gd::drop_late_snapshots(root); !notice.empty())
    if (PyErr_WarnEx(PyExc_UserWarning, notice.c_str(), 1) < 0) throw py::error_already_set();
  return root;
}

namespace {

using gd::python::model_root;

std::string config_text(const std::vector<std::string>& files, const std::vector<std::string>& sets,
                        std::optional<double> mu, std::optional<long long> seed) {
  const gd::ModelConfig cfg = gd::parse_config(model_root(files, sets, mu, seed));
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << gd::to_yaml(cfg);
  return out.c_str();
}

// The grid interval at which the run comes back to Python to look for a signal: at most this many
// steps (a fraction of a second of engine time), and a divisor of the recording interval.
constexpr std::int64_t kCheckSteps = 2000;

py::dict simulate(const std::vector<std::string>& files, const std::vector<std::string>& sets,
                  std::optional<double> mu, std::optional<long long> seed, int realizations, bool deterministic,
                  double rate) {
  if (realizations < 0) throw std::invalid_argument("realizations = " + std::to_string(realizations) + ": must be >= 0");
  if (!(rate >= 0)) throw std::invalid_argument("rate must be >= 0 Hz");
  const gd::ModelConfig pc = gd::parse_config(model_root(files, sets, mu, seed));
  std::vector<gd::LaneSpec> lanes;
  std::vector<std::string> names;
  if (deterministic) {
    lanes.push_back(gd::deterministic_lane(pc, pc.friction_coefficient));
    names.push_back("S1");
  }
  for (int r = 0; r < realizations; ++r) {
    lanes.push_back(gd::stochastic_lane(pc, pc.friction_coefficient, static_cast<std::uint64_t>(r)));
    names.push_back("r" + std::to_string(r));
  }
  if (lanes.empty()) throw std::invalid_argument("nothing to run: deterministic=False with realizations=0");

  const std::int64_t record_every =
      rate > 0 ? std::max<std::int64_t>(1, std::llround(1.0 / (rate * pc.run.time_step))) : 0;
  std::int64_t check_every = kCheckSteps;
  if (record_every > 0) {
    check_every = 1;
    for (std::int64_t k = std::min(record_every, kCheckSteps); k >= 1; --k)
      if (record_every % k == 0) { check_every = k; break; }
  }
  const std::size_t nl = lanes.size();
  std::vector<double> t, delta, delta_dot, phi, dist;  // sample-major: [sample][lane]
  // The bearings model's further outputs (gear_run's extra CSV columns), in the same layout.
  const bool bearings = pc.gear.model == gd::GearModel::kBearings;
  std::vector<std::vector<double>> outputs(bearings ? std::size(gd::kBearingsOutputs) : 0);  // kBearingsOutputs'
  gd::Ensemble ensemble(gd::derive(pc.gear), pc.run.time_step, pc.initial, lanes, pc.seed);
  gd::Recorder recorder;
  recorder.every = check_every;
  recorder.record = [&](const gd::Ensemble& e, const Eigen::ArrayXd& d) {
    if (record_every > 0 && e.step_index() % record_every == 0) {
      t.push_back(gd::grid_time(e.step_index(), e.time_step()));
      const gd::model_step::MeshPoint mesh =
          bearings ? gd::output_mesh_point(e.mesh(), e.time()) : gd::model_step::MeshPoint{};
      for (int i = 0; i < e.lanes(); ++i) {
        delta.push_back(e.delta()[i]);
        delta_dot.push_back(e.velocity()[i]);
        phi.push_back(e.load()[i]);
        dist.push_back(d[i]);
        if (bearings) {
          const gd::BearingsOutputs o = gd::bearings_outputs(e, mesh, i);
          for (std::size_t k = 0; k < outputs.size(); ++k) outputs[k].push_back(o.*gd::kBearingsOutputs[k].value);
        }
      }
    }
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw PythonInterrupt{};
  };
  std::vector<gd::RunResult> results;
  {
    py::gil_scoped_release release;
    try {
      results = gd::simulate(ensemble, pc.run, recorder);
    } catch (const PythonInterrupt&) {
      py::gil_scoped_acquire gil;
      throw py::error_already_set();
    }
  }
  const auto ns = static_cast<py::ssize_t>(t.size()), nr = static_cast<py::ssize_t>(nl);
  // Runs along the first axis, samples along the second, as the CSV's rows grouped by run.
  auto per_run = [&](const std::vector<double>& v) {
    py::array_t<double> a({nr, ns});
    auto m = a.mutable_unchecked<2>();
    for (py::ssize_t s = 0; s < ns; ++s)
      for (py::ssize_t r = 0; r < nr; ++r) m(r, s) = v[static_cast<std::size_t>(s * nr + r)];
    return a;
  };
  py::dict out;
  out["names"] = names;
  out["t"] = py::array_t<double>(ns, t.data());
  {
    const gd::GearPair gear = gd::derive(pc.gear);
    py::array_t<double> angle(ns);
    auto ma = angle.mutable_unchecked<1>();
    for (py::ssize_t s = 0; s < ns; ++s) ma(s) = gd::shaft_angle(gear, t[static_cast<std::size_t>(s)]);
    out["shaft_angle"] = angle;
  }
  out["delta"] = per_run(delta);
  out["delta_dot"] = per_run(delta_dot);
  out["phi"] = per_run(phi);
  out["center_distance"] = per_run(dist);
  for (std::size_t k = 0; k < outputs.size(); ++k) out[gd::kBearingsOutputs[k].name] = per_run(outputs[k]);
  auto column = [&](auto get) {
    py::array_t<double> a(nr);
    auto m = a.mutable_unchecked<1>();
    for (py::ssize_t r = 0; r < nr; ++r) m(r) = get(results[static_cast<std::size_t>(r)]);
    return a;
  };
  py::dict summary;
  summary["center_distance"] = column([](const gd::RunResult& r) { return r.center_distance; });
  summary["delta_range"] = column([](const gd::RunResult& r) { return r.delta_range; });
  summary["delta_dot_range"] = column([](const gd::RunResult& r) { return r.delta_dot_range; });
  summary["steady_state_time"] = column([](const gd::RunResult& r) { return r.steady_state_time; });
  summary["steady_state_time_fine"] = column([](const gd::RunResult& r) { return r.steady_state_time_fine; });
  summary["reached_steady_state"] =
      column([](const gd::RunResult& r) { return r.reached_steady_state ? 1.0 : 0.0; });
  summary["final_delta"] = column([](const gd::RunResult& r) { return r.final_delta; });
  summary["final_delta_dot"] = column([](const gd::RunResult& r) { return r.final_delta_dot; });
  summary["final_load"] = column([](const gd::RunResult& r) { return r.final_load; });
  out["summary"] = summary;
  out["seed"] = pc.seed;
  out["time_step"] = pc.run.time_step;
  out["duration"] = pc.run.duration;
  return out;
}

// The potential-energy stiffness of one tooth pair along the line of action (model/tooth_stiffness.hpp)
// for the configured gear, its crack and spall included: x over [x_a, x_e] at `points` points.
py::dict tooth_pair_stiffness(const std::vector<std::string>& files, const std::vector<std::string>& sets,
                              int pinion_tooth, int wheel_tooth, int points, bool fillet_foundation) {
  if (points < 2) throw std::invalid_argument("points = " + std::to_string(points) + ": must be >= 2");
  const gd::ModelConfig pc = gd::parse_config(model_root(files, sets, std::nullopt, std::nullopt));
  const gd::GearPair gear = gd::derive(pc.gear);
  gd::PotentialEnergyOptions options;
  options.fillet_foundation = fillet_foundation;
  const gd::ToothPairStiffness pair(gear, options);
  const auto n = static_cast<py::ssize_t>(points);
  py::array_t<double> x(n), k(n), hertz(n), bending(n), shear(n), axial(n), foundation(n);
  auto mx = x.mutable_unchecked<1>(), mk = k.mutable_unchecked<1>(), mh = hertz.mutable_unchecked<1>(),
       mb = bending.mutable_unchecked<1>(), ms = shear.mutable_unchecked<1>(), ma = axial.mutable_unchecked<1>(),
       mf = foundation.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const double xi = gear.x_a + (gear.x_e - gear.x_a) * static_cast<double>(i) / static_cast<double>(n - 1);
    const gd::PairCompliance c = pair.compliance(xi, pinion_tooth, wheel_tooth);
    mx(i) = xi;
    mk(i) = 1.0 / c.total();
    mh(i) = c.hertz;
    mb(i) = c.bending[0] + c.bending[1];
    ms(i) = c.shear[0] + c.shear[1];
    ma(i) = c.axial[0] + c.axial[1];
    mf(i) = c.foundation[0] + c.foundation[1];
  }
  py::dict out;
  out["x"] = x;
  out["stiffness"] = k;
  out["hertz"] = hertz;
  out["bending"] = bending;
  out["shear"] = shear;
  out["axial"] = axial;
  out["foundation"] = foundation;
  out["x_a"] = gear.x_a;
  out["x_e"] = gear.x_e;
  out["base_pitch"] = gear.base_pitch;
  return out;
}

py::dict spectrum(const std::vector<double>& x, double sample_rate, std::size_t segment, double overlap) {
  gd::WelchOptions o;
  o.segment = segment;
  o.overlap = overlap;
  gd::Psd p;
  {
    py::gil_scoped_release release;
    p = gd::welch_psd(x, sample_rate, o);
  }
  py::dict out;
  out["frequency"] = py::array_t<double>(static_cast<py::ssize_t>(p.frequency.size()), p.frequency.data());
  out["density"] = py::array_t<double>(static_cast<py::ssize_t>(p.density.size()), p.density.data());
  out["resolution"] = p.resolution;
  out["enbw"] = p.enbw;
  out["segments"] = p.segments;
  return out;
}

// S1 of the configuration as one deterministic lane (dynamics/system.hpp).
gd::GearLaneSpec s1_lane(const gd::ModelConfig& c) {
  return gd::GearLaneSpec{c.gear, c.friction_coefficient, c.load.initial_mean, c.initial};
}

py::array_t<double> vec(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

// S1's Poincare section at mesh phase 0 (as gear_analyze poincare and the batch's /gear/poincare).
py::dict poincare(const std::vector<std::string>& files, const std::vector<std::string>& sets, std::optional<double> mu,
                  double transient) {
  const gd::ModelConfig c = gd::parse_config(model_root(files, sets, mu, std::nullopt));
  if (!(transient >= 0 && transient <= c.run.duration))
    throw std::invalid_argument("transient = " + std::to_string(transient) + " s is out of range; allowed [0, run.duration = " +
                                std::to_string(c.run.duration) + "] s");
  const gd::GearPair g = gd::derive(c.gear);
  std::vector<gd::SectionState> st;
  {
    py::gil_scoped_release release;
    gd::GearLanes sys({s1_lane(c)}, c.run.time_step);
    st = gd::poincare_section(sys, {gd::mesh_period(g), gd::first_mesh_period_start(g), transient, c.run.duration, {}});
  }
  std::vector<double> t, d, v, on;
  for (const auto& p : st) {
    t.push_back(p.time);
    d.push_back(p.x[0]);
    v.push_back(p.x[1]);
    on.push_back(p.on_grid ? 1.0 : 0.0);
  }
  py::dict out;
  out["t"] = vec(t);
  out["delta"] = vec(d);
  out["delta_dot"] = vec(v);
  out["on_grid"] = vec(on);
  out["mesh_period"] = gd::mesh_period(g);
  return out;
}

// S1's Lyapunov spectrum (lambda1 >= lambda2 ..., one per state component: two for the torsional
// model, ten for the bearings model) by QR of the tangent map (dynamics/lyapunov.hpp).
py::dict lyapunov(const std::vector<std::string>& files, const std::vector<std::string>& sets, std::optional<double> mu,
                  double duration, std::int64_t orthonormalise_every) {
  const gd::ModelConfig c = gd::parse_config(model_root(files, sets, mu, std::nullopt));
  if (!(duration > 0)) throw std::invalid_argument("duration = " + std::to_string(duration) + " s: must be > 0");
  gd::SpectrumOptions o;
  o.duration = duration;
  o.orthonormalise_every = orthonormalise_every;
  gd::LyapunovSpectrum r;
  {
    py::gil_scoped_release release;
    r = gd::lyapunov_spectrum(s1_lane(c), c.run.time_step, o);
  }
  py::dict out;
  out["exponents"] = r.exponent;
  out["trace"] = r.trace;
  out["time"] = vec(r.time);
  out["running"] = vec(r.running);
  return out;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "The compiled core of gear_dynamics (use the gear_dynamics package, not this module).";
  py::register_exception<gd::ConfigError>(m, "ConfigError", PyExc_ValueError).doc() =
      "A configuration value or key the package refuses: the text names the parameter, the value and "
      "the allowed range, as gear_run prints it.";
  m.def("config_dir", &gd::config_dir, "The folder of the default configuration (gear_run's search).");
  m.def("config_text", &config_text, py::arg("files"), py::arg("sets"), py::arg("mu"), py::arg("seed"),
        "The validated configuration as YAML text.");
  m.def("simulate", &simulate, py::arg("files"), py::arg("sets"), py::arg("mu"), py::arg("seed"),
        py::arg("realizations"), py::arg("deterministic"), py::arg("rate"),
        "Runs S1 and realizations as gear_run does; a dict of numpy arrays.");
  m.def("spectrum", &spectrum, py::arg("x"), py::arg("sample_rate"), py::arg("segment"), py::arg("overlap"),
        "Welch's one-sided power spectral density (maths/spectrum.hpp).");
  m.def("poincare", &poincare, py::arg("files"), py::arg("sets"), py::arg("mu"), py::arg("transient"),
        "S1's Poincare section at mesh phase 0.");
  m.def("lyapunov", &lyapunov, py::arg("files"), py::arg("sets"), py::arg("mu"), py::arg("duration"),
        py::arg("orthonormalise_every"), "S1's Lyapunov spectrum.");
  m.def("tooth_pair_stiffness", &tooth_pair_stiffness, py::arg("files"), py::arg("sets"), py::arg("pinion_tooth"),
        py::arg("wheel_tooth"), py::arg("points"), py::arg("fillet_foundation"),
        "One tooth pair's potential-energy stiffness along the line of action.");
  gd::python::bind_ensemble(m);
  gd::python::bind_monitor(m);
}
