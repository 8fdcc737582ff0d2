#include "gear_dynamics/config/config.hpp"

#include <cmath>
#include <sstream>

namespace gear_dynamics {

namespace {

constexpr double kPi = 3.14159265358979323846;
using detail::throw_if_errors;

}  // namespace

const std::vector<Section<ModelConfig>>& model_sections() {
  static const std::vector<Section<ModelConfig>> sections = {
      Section<ModelConfig>("gear_pair", "gear_pair.")
          .key("density", GD_MEMBER(gear.density), open(0, kInf), "kg/m^3", "rho, material density")
          .key("youngs_modulus", GD_MEMBER(gear.youngs_modulus), open(0, kInf), "Pa", "E, Young's modulus")
          .key("poisson_ratio", GD_MEMBER(gear.poisson_ratio), closed_open(0, 0.5), "-",
               "nu, Poisson's ratio (not used by the stiffness model)")
          .key("pinion_pitch_radius", GD_MEMBER(gear.pinion_pitch_radius), open(0, kInf), "m", "r1, pinion pitch radius")
          .key("gear_pitch_radius", GD_MEMBER(gear.gear_pitch_radius), open(0, kInf), "m", "r2, gear pitch radius")
          .key("pressure_angle", GD_MEMBER(gear.pressure_angle), open_closed(0, kPi / 4), "rad", "alpha0, pressure angle")
          .key("pinion_teeth", GD_MEMBER(gear.pinion_teeth), closed(5, 10000), "-", "Z1, pinion teeth")
          .key("gear_teeth", GD_MEMBER(gear.gear_teeth), closed(5, 10000), "-", "Z2, gear teeth")
          .key("face_width", GD_MEMBER(gear.face_width), open(0, kInf), "m", "L, face width")
          .key("backlash", GD_MEMBER(gear.backlash), closed(0, 1e-3), "m", "b, half the clearance of Eq. 17")
          .key("addendum_coefficient", GD_MEMBER(gear.addendum_coefficient), open_closed(0, 2), "-",
               "h_a/m; with the teeth and angle the contact ratio must lie in (1, 2)")
          .key("dedendum_coefficient", GD_MEMBER(gear.dedendum_coefficient), open_closed(0, 2), "-", "h_f/m")
          .key("pinion_speed", GD_MEMBER(gear.pinion_speed), closed(0, 1e4), "rad/s",
               "Omega, pinion speed; a time step must not span a stiffness interval")
          .key("damping_ratio", GD_MEMBER(gear.damping_ratio), closed(0, 1), "-", "zeta_ref at reference_load")
          .key("reference_load", GD_MEMBER(gear.reference_load), open(0, kInf), "N", "F_ref at which damping_ratio holds")
          .key("mesh_phase", GD_MEMBER(gear.mesh_phase), closed_open(0, 2 * kPi), "rad",
               "phi0, initial mesh phase; below one mesh period 2 pi / pinion_teeth")
          .key("friction_coefficient", GD_MEMBER(friction_coefficient), closed(0, kMaxFrictionCoefficient), "-",
               "mu, tooth friction coefficient")
          .key("initial_deflection", GD_MEMBER(initial.deflection), closed(-1e-2, 1e-2), "m", "delta(0)")
          .key("initial_velocity", GD_MEMBER(initial.velocity), closed(-10, 10), "m/s", "delta_dot(0)"),
      Section<ModelConfig>("load", "load.")
          .key("initial_mean", GD_MEMBER(load.initial_mean), closed(-kMaxLoadMean, kMaxLoadMean), "m/s^2",
               "E[Phi(0)]; the deterministic run S1 keeps Phi at this value")
          .key("initial_sd", GD_MEMBER(load.initial_sd), closed(0, 1e4), "m/s^2", "sd of Phi(0), normal")
          .key("drift", GD_MEMBER(load.drift), closed(-kMaxLoadDrift, kMaxLoadDrift), "m/s^3", "lambda, drift of Phi")
          .key("sigma", GD_MEMBER(load.sigma), closed(0, kMaxLoadSigma), "m/s^2/sqrt(s)", "sigma, noise intensity of Phi"),
      Section<ModelConfig>("run", "run.")
          .key("time_step", GD_MEMBER(run.time_step), open_closed(0, 1e-4), "s",
               "h, fixed RK4 step; small enough for the stiffest contact")
          .key("duration", GD_MEMBER(run.duration), open_closed(0, 1e4), "s", "T, a whole number of time steps")
          // Below 2^53: every accepted seed is exact as a double (YAML numbers are read as one).
          .key("seed", GD_MEMBER(seed), closed(0, 9007199254740991.0), "-", "seed of the counter-based random streams")
          .key("window", GD_MEMBER(run.window), open(0, kInf), "s",
               "W, center-distance window [T - W, T]; at most duration")
          .key("snapshot_times", GD_MEMBER(run.snapshot_times), closed_open(0, kInf), "s",
               "increasing grid times in [0, duration] at which the state is kept")
          .may_be_empty()
          .key("steady_state_tolerance", GD_MEMBER(run.steady_state_tolerance), open_closed(0, 1), "fraction of b",
               "t_ss threshold")
          .key("steady_state_tolerance_fine", GD_MEMBER(run.steady_state_tolerance_fine), open_closed(0, 1),
               "fraction of b", "secondary t_ss threshold, at most steady_state_tolerance"),
  };
  return sections;
}

void validate_consistency(const ModelConfig& c) {
  std::vector<std::string> errors;
  const GearPair g = derive(c.gear);
  std::ostringstream e;
  e.precision(12);
  if (!(g.contact_ratio > 1.0 && g.contact_ratio < 2.0)) {
    e << "gear_pair: contact ratio " << g.contact_ratio << " (from pinion_teeth = " << c.gear.pinion_teeth
      << ", gear_teeth = " << c.gear.gear_teeth << ", pressure_angle = " << c.gear.pressure_angle
      << ", addendum_coefficient = " << c.gear.addendum_coefficient
      << ") is outside (1, 2), the range of the two-level stiffness model";
    errors.push_back(e.str());
    e.str("");
  }
  if (!(c.gear.mesh_phase < g.mesh_period_angle)) {
    e << "gear_pair.mesh_phase = " << c.gear.mesh_phase << " is out of range; allowed [0, "
      << g.mesh_period_angle << ") rad (one mesh period 2 pi / pinion_teeth)";
    errors.push_back(e.str());
    e.str("");
  }
  const double h = c.run.time_step;
  if (errors.empty()) {
    const double wh = g.max_contact_frequency(kMaxFrictionCoefficient) * h;
    if (!(wh < kMaxOmegaTimesStep)) {
      e << "run.time_step = " << h << " s is too large for the stiffest contact: omega_max h = " << wh
        << " with omega_max = " << wh / h << " rad/s at mu = " << kMaxFrictionCoefficient
        << "; RK4 needs omega_max h < " << kMaxOmegaTimesStep << " (stability), i.e. time_step < "
        << kMaxOmegaTimesStep / (wh / h) << " s; doc/model.md §5's accuracy figures hold for omega_max h <= 0.18";
      errors.push_back(e.str());
      e.str("");
    }
    const double shortest = std::min(g.single_pair_angle, g.mesh_period_angle - g.single_pair_angle);
    if (c.gear.pinion_speed * h >= shortest) {
      e << "run.time_step = " << h << " s spans a whole stiffness interval at pinion_speed = "
        << c.gear.pinion_speed << " rad/s; allowed time_step < " << shortest / c.gear.pinion_speed << " s";
      errors.push_back(e.str());
      e.str("");
    }
  }
  const double steps = c.run.duration / h;
  if (std::abs(steps - std::round(steps)) > 1e-9 * steps) {
    e << "run.duration = " << c.run.duration << " s is not a whole number of time steps (" << steps
      << " x " << h << " s)";
    errors.push_back(e.str());
    e.str("");
  }
  if (!(c.run.window <= c.run.duration)) {
    e << "run.window = " << c.run.window << " s is out of range; allowed (0, duration = "
      << c.run.duration << "] s";
    errors.push_back(e.str());
    e.str("");
  }
  for (std::size_t i = 0; i < c.run.snapshot_times.size(); ++i) {
    const double t = c.run.snapshot_times[i], k = t / h;
    if (t > c.run.duration || std::abs(k - std::round(k)) > 1e-9 * std::max(k, 1.0)) {
      e << "run.snapshot_times[" << i << "] = " << t << " s is not a grid time in [0, duration = "
        << c.run.duration << "] s with time_step " << h << " s";
      errors.push_back(e.str());
      e.str("");
    }
    if (i > 0 && t <= c.run.snapshot_times[i - 1]) {
      e << "run.snapshot_times[" << i << "] = " << t << " s is not after the previous one; the list must increase";
      errors.push_back(e.str());
      e.str("");
    }
  }
  if (c.run.steady_state_tolerance_fine > c.run.steady_state_tolerance) {
    e << "run.steady_state_tolerance_fine = " << c.run.steady_state_tolerance_fine
      << " is above run.steady_state_tolerance = " << c.run.steady_state_tolerance
      << "; allowed (0, steady_state_tolerance]";
    errors.push_back(e.str());
  }
  throw_if_errors(errors);
}

ModelConfig parse_config(const YAML::Node& root) {
  ModelConfig c;
  std::vector<std::string> errors;
  if (!root.IsMap()) throw ConfigError("invalid configuration: the top level must be a map with the sections gear_pair, load and run");
  for (const Section<ModelConfig>& section : model_sections()) {
    const YAML::Node node = root[section.name()];
    if (!node) {
      errors.push_back("missing section '" + section.name() + "'");
    } else if (!node.IsMap()) {
      errors.push_back(section.name() + " must be a map of keys, got " + detail::show(node));
    } else {
      SectionReader in(node, section.prefix(), errors);
      section.read(in, c);
      in.finish();
    }
  }
  throw_if_errors(errors);
  validate_consistency(c);  // only meaningful once every value is in range
  return c;
}

void merge_yaml(YAML::Node& base, const YAML::Node& overlay) {
  if (!overlay.IsMap() || !base.IsMap()) {
    base = overlay;
    return;
  }
  for (const auto& kv : overlay) {
    const std::string key = kv.first.as<std::string>();
    YAML::Node child = base[key];
    if (child && child.IsMap() && kv.second.IsMap()) {
      merge_yaml(child, kv.second);
    } else {
      base[key] = YAML::Clone(kv.second);
    }
  }
}

YAML::Node read_yaml_files(const std::vector<std::string>& files) {
  YAML::Node root(YAML::NodeType::Map);
  for (const std::string& file : files) {
    YAML::Node doc;
    try {
      doc = YAML::LoadFile(file);
    } catch (const YAML::BadFile&) {
      throw ConfigError("cannot read configuration file '" + file + "'");
    } catch (const YAML::Exception& ex) {
      throw ConfigError("configuration file '" + file + "' is not valid YAML: " + ex.what());
    }
    if (!doc || doc.IsNull()) continue;
    if (!doc.IsMap()) throw ConfigError("configuration file '" + file + "' must hold a map at its top level");
    merge_yaml(root, doc);
  }
  return root;
}

YAML::Node to_yaml(const ModelConfig& config) {
  YAML::Node root;
  for (const Section<ModelConfig>& section : model_sections()) root[section.name()] = section.to_yaml(config);
  return root;
}

LaneSpec stochastic_lane(const ModelConfig& config, double mu, std::uint64_t realization) {
  LaneSpec s;
  s.mu = mu;
  s.sigma = config.load.sigma;
  s.drift = config.load.drift;
  s.load_mean = config.load.initial_mean;
  s.load_sd = config.load.initial_sd;
  s.realization = realization;
  return s;
}

LaneSpec deterministic_lane(const ModelConfig& config, double mu) {
  LaneSpec s;
  s.mu = mu;
  s.load_mean = config.load.initial_mean;
  s.stochastic = false;
  return s;
}

}  // namespace gear_dynamics
