#include "gear_dynamics/config/config.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

namespace gear_dynamics {

namespace detail {

std::string show(const YAML::Node& n) {
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

bool as_number(const YAML::Node& n, double& out) {
  if (!n.IsScalar()) return false;
  const std::string& s = n.Scalar();
  if (s == "true" || s == "false" || s == "True" || s == "False") return false;
  try {
    out = n.as<double>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

void throw_if_errors(const std::vector<std::string>& errors) {
  if (errors.empty()) return;
  std::string all = "invalid configuration:";
  for (const auto& m : errors) all += "\n  " + m;
  throw ConfigError(all);
}

}  // namespace detail

namespace {

using detail::as_number;
using detail::show;
using detail::throw_if_errors;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

using Kind = KeyKind;

// One key of the schema: its range (closed unless `open_*`), unit and where it goes.
struct Field {
  const char* key;
  Kind kind;
  double lo, hi;
  bool open_lo, open_hi;
  const char* unit;
  std::function<void(ModelConfig&, double)> set;                       // Real, Integer
  std::function<void(ModelConfig&, const std::vector<double>&)> set_list;  // RealList
  std::function<YAML::Node(const ModelConfig&)> get;
};

struct Section {
  const char* name;
  std::vector<Field> fields;
};

// A real-valued key stored in the member that `ref` returns.
Field real(const char* key, double lo, double hi, bool open_lo, bool open_hi, const char* unit,
           double& (*ref)(ModelConfig&)) {
  return Field{key, Kind::Real, lo, hi, open_lo, open_hi, unit,
               [ref](ModelConfig& c, double v) { ref(c) = v; }, nullptr,
               [ref](const ModelConfig& c) { return YAML::Node(ref(const_cast<ModelConfig&>(c))); }};
}

#define GD_REAL(key, lo, hi, olo, ohi, unit, member) \
  real(key, lo, hi, olo, ohi, unit, [](ModelConfig& c) -> double& { return c.member; })

Field integer(const char* key, double lo, double hi, const char* unit,
              std::function<void(ModelConfig&, double)> set,
              std::function<YAML::Node(const ModelConfig&)> get) {
  return Field{key, Kind::Integer, lo, hi, false, false, unit, std::move(set), nullptr, std::move(get)};
}

const std::vector<Section>& schema() {
  static const std::vector<Section> sections = {
      {"gear_pair",
       {GD_REAL("density", 0, kInf, true, true, "kg/m^3", gear.density),
        GD_REAL("youngs_modulus", 0, kInf, true, true, "Pa", gear.youngs_modulus),
        GD_REAL("poisson_ratio", 0, 0.5, false, true, "-", gear.poisson_ratio),
        GD_REAL("pinion_pitch_radius", 0, kInf, true, true, "m", gear.pinion_pitch_radius),
        GD_REAL("gear_pitch_radius", 0, kInf, true, true, "m", gear.gear_pitch_radius),
        GD_REAL("pressure_angle", 0, kPi / 4, true, false, "rad", gear.pressure_angle),
        integer("pinion_teeth", 5, 10000, "-",
                [](ModelConfig& c, double v) { c.gear.pinion_teeth = static_cast<int>(v); },
                [](const ModelConfig& c) { return YAML::Node(c.gear.pinion_teeth); }),
        integer("gear_teeth", 5, 10000, "-",
                [](ModelConfig& c, double v) { c.gear.gear_teeth = static_cast<int>(v); },
                [](const ModelConfig& c) { return YAML::Node(c.gear.gear_teeth); }),
        GD_REAL("face_width", 0, kInf, true, true, "m", gear.face_width),
        GD_REAL("backlash", 0, 1e-3, false, false, "m", gear.backlash),
        GD_REAL("addendum_coefficient", 0, 2, true, false, "-", gear.addendum_coefficient),
        GD_REAL("dedendum_coefficient", 0, 2, true, false, "-", gear.dedendum_coefficient),
        GD_REAL("pinion_speed", 0, 1e4, false, false, "rad/s", gear.pinion_speed),
        GD_REAL("damping_ratio", 0, 1, false, false, "-", gear.damping_ratio),
        GD_REAL("reference_load", 0, kInf, true, true, "N", gear.reference_load),
        GD_REAL("mesh_phase", 0, 2 * kPi, false, true, "rad", gear.mesh_phase),
        GD_REAL("friction_coefficient", 0, kMaxFrictionCoefficient, false, false, "-", friction_coefficient),
        GD_REAL("initial_deflection", -1e-2, 1e-2, false, false, "m", initial.deflection),
        GD_REAL("initial_velocity", -10, 10, false, false, "m/s", initial.velocity)}},
      {"load",
       {GD_REAL("initial_mean", -1e4, 1e4, false, false, "m/s^2", load.initial_mean),
        GD_REAL("initial_sd", 0, 1e4, false, false, "m/s^2", load.initial_sd),
        GD_REAL("drift", -kMaxLoadDrift, kMaxLoadDrift, false, false, "m/s^3", load.drift),
        GD_REAL("sigma", 0, kMaxLoadSigma, false, false, "m/s^2/sqrt(s)", load.sigma)}},
      {"run",
       {GD_REAL("time_step", 0, 1e-4, true, false, "s", run.time_step),
        GD_REAL("duration", 0, 1e4, true, false, "s", run.duration),
        // Below 2^53: every accepted seed is exact as a double (YAML numbers are read as one).
        integer("seed", 0, 9007199254740991.0, "-",
                [](ModelConfig& c, double v) { c.seed = static_cast<std::uint64_t>(v); },
                [](const ModelConfig& c) { return YAML::Node(c.seed); }),
        GD_REAL("window", 0, kInf, true, true, "s", run.window),
        Field{"snapshot_times", Kind::RealList, 0, kInf, false, true, "s", nullptr,
              [](ModelConfig& c, const std::vector<double>& v) { c.run.snapshot_times = v; },
              [](const ModelConfig& c) {
                YAML::Node n;
                for (double t : c.run.snapshot_times) n.push_back(t);
                n.SetStyle(YAML::EmitterStyle::Flow);
                return n;
              }},
        GD_REAL("steady_state_tolerance", 0, 1, true, false, "fraction of b", run.steady_state_tolerance),
        GD_REAL("steady_state_tolerance_fine", 0, 1, true, false, "fraction of b",
                run.steady_state_tolerance_fine)}},
  };
  return sections;
}

#undef GD_REAL

std::string range_text(const Field& f) {
  std::ostringstream s;
  if (f.kind == Kind::Integer) s.precision(17);
  s << (f.open_lo ? "(" : "[") << f.lo << ", " << f.hi << (f.open_hi ? ")" : "]");
  if (f.kind == Kind::Integer) s << " (integer)";
  s << " " << f.unit;
  return s.str();
}

bool in_range(const Field& f, double v) {
  return (f.open_lo ? v > f.lo : v >= f.lo) && (f.open_hi ? v < f.hi : v <= f.hi);
}

void check_value(const Field& f, const std::string& path, double v, std::vector<std::string>& errors) {
  std::ostringstream e;
  e.precision(f.kind == Kind::Integer ? 17 : 12);
  if (!std::isfinite(v)) {
    e << path << " = " << v << " is not finite; allowed " << range_text(f);
  } else if (f.kind == Kind::Integer && v != std::floor(v)) {
    e << path << " = " << v << " is not an integer; allowed " << range_text(f);
  } else if (!in_range(f, v)) {
    e << path << " = " << v << " is out of range; allowed " << range_text(f);
  } else {
    return;
  }
  errors.push_back(e.str());
}

}  // namespace

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
        << kMaxOmegaTimesStep / (wh / h) << " s; doc/model.md's accuracy needs omega_max h <= 0.07";
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

std::vector<KeySpec> config_schema() {
  std::vector<KeySpec> keys;
  for (const Section& s : schema())
    for (const Field& f : s.fields) keys.push_back({s.name, f.key, f.kind, f.lo, f.hi, f.open_lo, f.open_hi, f.unit});
  return keys;
}

ModelConfig parse_config(const YAML::Node& root) {
  ModelConfig c;
  std::vector<std::string> errors;
  if (!root.IsMap()) throw ConfigError("invalid configuration: the top level must be a map with the sections gear_pair, load and run");
  for (const Section& section : schema()) {
    const YAML::Node node = root[section.name];
    if (!node) {
      errors.push_back(std::string("missing section '") + section.name + "'");
      continue;
    }
    if (!node.IsMap()) {
      errors.push_back(std::string(section.name) + " must be a map of keys, got " + show(node));
      continue;
    }
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      bool known = false;
      for (const Field& f : section.fields) known = known || key == f.key;
      if (!known) {
        std::string valid;
        for (const Field& f : section.fields) valid += std::string(valid.empty() ? "" : ", ") + f.key;
        errors.push_back(std::string(section.name) + "." + key + " is not a known key (a typo?); valid keys: " + valid);
      }
    }
    for (const Field& f : section.fields) {
      const std::string path = std::string(section.name) + "." + f.key;
      const YAML::Node v = node[f.key];
      if (!v || v.IsNull()) {
        errors.push_back(path + " is missing; allowed " + range_text(f));
        continue;
      }
      if (f.kind == Kind::RealList) {
        if (!v.IsSequence()) {
          errors.push_back(path + " = " + show(v) + " has the wrong type: expected a list of numbers in " + range_text(f));
          continue;
        }
        std::vector<double> list;
        for (std::size_t i = 0; i < v.size(); ++i) {
          double x;
          const std::string item = path + "[" + std::to_string(i) + "]";
          if (!as_number(v[i], x)) {
            errors.push_back(item + " = " + show(v[i]) + " has the wrong type: expected a number in " + range_text(f));
            continue;
          }
          const std::size_t before = errors.size();
          check_value(f, item, x, errors);
          if (errors.size() == before) list.push_back(x);
        }
        f.set_list(c, list);
        continue;
      }
      double x;
      if (!as_number(v, x)) {
        errors.push_back(path + " = " + show(v) + " has the wrong type: expected a number in " + range_text(f));
        continue;
      }
      const std::size_t before = errors.size();
      check_value(f, path, x, errors);
      if (errors.size() == before) f.set(c, x);
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
  for (const Section& section : schema()) {
    for (const Field& f : section.fields) root[section.name][f.key] = f.get(config);
  }
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
