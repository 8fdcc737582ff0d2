#include "gear_dynamics/config/config.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"
#include "gear_dynamics/model/friction_law.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

namespace gear_dynamics {

// The mesh options as YAML texts: a text key whose choices are the names, in enum order.
template <class E>
struct EnumNames;
template <>
struct EnumNames<MeshStiffnessModel> {
  static std::vector<std::string> names() { return {"square_wave", "potential_energy"}; }
};
template <>
struct EnumNames<FrictionDirection> {
  static std::vector<std::string> names() { return {"constant", "reversing"}; }
};
template <>
struct EnumNames<FrictionModel> {
  static std::vector<std::string> names() { return friction_model_names(); }
};
template <>
struct EnumNames<GearModel> {
  static std::vector<std::string> names() { return {"torsional", "bearings"}; }
};
template <>
struct EnumNames<FaultyGear> {
  static std::vector<std::string> names() { return {"none", "pinion", "wheel"}; }
};
template <class E>
struct Codec<E, std::enable_if_t<std::is_enum_v<E>>> {
  static constexpr KeyKind kind = KeyKind::Text;
  static constexpr std::size_t size = 0;
  static void set(E& m, const Value& v) {
    const std::vector<std::string> n = EnumNames<E>::names();
    m = static_cast<E>(std::find(n.begin(), n.end(), v.text) - n.begin());
  }
  static YAML::Node get(E m) { return YAML::Node(EnumNames<E>::names().at(static_cast<std::size_t>(m))); }
};

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
          .key("friction_direction", GD_MEMBER(gear.friction_direction),
               "constant: the paper's sign; reversing: reversed at the pitch point")
          .one_of(EnumNames<FrictionDirection>::names())
          .key("friction_model", GD_MEMBER(gear.friction_model),
               "constant: mu = friction_coefficient; benedict_kelley, xu, iso_tr_13989: a law per pair, "
               "scaled by friction_coefficient / 0.04")
          .one_of(friction_model_names())
          .omitted_at_default()
          .key("friction_load", GD_MEMBER(gear.friction_load), closed(1e-3, 1e7), "N",
               "W, static mesh force a friction law is evaluated at (shared by the pairs as their stiffness)")
          .omitted_at_default()
          .key("oil_viscosity", GD_MEMBER(gear.oil_viscosity), closed(1e-3, 10), "Pa s",
               "eta, dynamic viscosity at the operating temperature (friction laws; ISO VG 100 at 70 C)")
          .omitted_at_default()
          .key("surface_roughness", GD_MEMBER(gear.surface_roughness), closed(0.01e-6, 1.2e-6), "m",
               "Ra, composite flank roughness (friction laws); below Benedict-Kelley's 50 micro-inch")
          .omitted_at_default()
          .key("mesh_stiffness", GD_MEMBER(gear.mesh_stiffness),
               "square_wave: the paper's two ISO 6336 levels; potential_energy: from the tooth geometry")
          .one_of(EnumNames<MeshStiffnessModel>::names())
          .key("profile_shift1", GD_MEMBER(gear.profile_shift1), closed(-1, 1.5), "-", "x1, pinion profile shift")
          .key("profile_shift2", GD_MEMBER(gear.profile_shift2), closed(-1, 1.5), "-", "x2, wheel profile shift")
          .key("bore_radius1", GD_MEMBER(gear.bore_radius1), open(0, kInf), "m",
               "pinion bore radius (fillet foundation); below the root radius")
          .key("bore_radius2", GD_MEMBER(gear.bore_radius2), open(0, kInf), "m",
               "wheel bore radius (fillet foundation); below the root radius")
          .key("crack_gear", GD_MEMBER(gear.crack.gear), "gear with a root crack: none, pinion or wheel")
          .one_of(EnumNames<FaultyGear>::names())
          .key("crack_tooth", GD_MEMBER(gear.crack.tooth), closed(0, 9999), "-",
               "cracked tooth; tooth 0 is in contact at theta1 = 0; below that gear's teeth")
          .key("crack_depth", GD_MEMBER(gear.crack.depth), closed(0, 0.1), "m", "q, crack depth")
          .key("crack_angle", GD_MEMBER(gear.crack.angle), open_closed(0, kPi / 2), "rad",
               "upsilon, crack angle to the tooth's centre line")
          .key("spall_gear", GD_MEMBER(gear.spall.gear), "gear with a spall: none, pinion or wheel")
          .one_of(EnumNames<FaultyGear>::names())
          .key("spall_tooth", GD_MEMBER(gear.spall.tooth), closed(0, 9999), "-", "spalled tooth; below that gear's teeth")
          .key("spall_length", GD_MEMBER(gear.spall.length), closed(0, 0.1), "m", "spall extent along the line of action")
          .key("spall_width", GD_MEMBER(gear.spall.width), closed(0, 1), "m", "spall extent across the face; at most face_width")
          .key("spall_position", GD_MEMBER(gear.spall.position), closed(0, 10), "m",
               "radius of the spall's centre on its tooth, within the active profile")
          .key("pinion_profile_errors", GD_MEMBER(profile_errors.pinion), closed(-1e-3, 1e-3), "m",
               "profile error of pinion teeth 0, 1, ... (static transmission error); the rest 0")
          .may_be_empty()
          .key("wheel_profile_errors", GD_MEMBER(profile_errors.wheel), closed(-1e-3, 1e-3), "m",
               "profile error of wheel teeth 0, 1, ...; the rest 0")
          .may_be_empty()
          .key("profile_error_sd", GD_MEMBER(profile_errors.sd), closed(0, 1e-3), "m",
               "sd of a normal profile error per tooth of both gears, drawn from run.seed, added")
          .key("model", GD_MEMBER(gear.model),
               "torsional: the one-degree-of-freedom model; bearings: both gears also translate on their bearings")
          .one_of(EnumNames<GearModel>::names())
          .omitted_at_default()
          .key("bearing_stiffness", GD_MEMBER(gear.bearing_stiffness), closed(1e5, 1e13), "N/m",
               "k_b, stiffness of each bearing in x and y (bearings model)")
          .omitted_at_default()
          .key("bearing_damping_ratio", GD_MEMBER(gear.bearing_damping_ratio), closed(0, 1), "-",
               "zeta_b, bearing damping c = 2 zeta_b sqrt(k_b m) (bearings model)")
          .omitted_at_default()
          .key("pinion_mass", GD_MEMBER(gear.pinion_mass), closed(0, 1e6), "kg",
               "m_p (bearings model); 0: a solid disc of the pitch radius, rho pi r1^2 L")
          .omitted_at_default()
          .key("wheel_mass", GD_MEMBER(gear.wheel_mass), closed(0, 1e6), "kg",
               "m_g (bearings model); 0: a solid disc of the pitch radius, rho pi r2^2 L")
          .omitted_at_default()
          .key("initial_deflection", GD_MEMBER(initial.deflection), closed(-1e-2, 1e-2), "m", "delta(0)")
          .key("initial_velocity", GD_MEMBER(initial.velocity), closed(-10, 10), "m/s", "delta_dot(0)"),
      Section<ModelConfig>("load", "load.")
          .key("initial_mean", GD_MEMBER(load.initial_mean), closed(-kMaxConfigLoadMean, kMaxConfigLoadMean), "m/s^2",
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

namespace {

// The faults, bores and profile errors against the geometry of `g` (doc/model.md §3).
// A friction law outside its published range is allowed (the paper's light load is far below every
// law's) but said once per message on stderr, naming the key and the range.
void warn_friction_law(const GearPair& g) {
  static std::mutex mutex;
  static std::set<std::string> said;
  for (const std::string& w : friction_law_warnings(g)) {
    const std::lock_guard<std::mutex> lock(mutex);
    if (said.insert(w).second) std::cerr << "warning: " << w << "\n";
  }
}

void validate_mesh(const ModelConfig& c, const GearPair& g, std::vector<std::string>& errors) {
  const GearInputs& in = c.gear;
  std::ostringstream e;
  e.precision(12);
  const auto flush = [&] { errors.push_back(e.str()), e.str(""); };
  const auto teeth = [&](FaultyGear f) { return f == FaultyGear::kWheel ? in.gear_teeth : in.pinion_teeth; };
  const auto gear_name = [](FaultyGear f) { return f == FaultyGear::kWheel ? "wheel" : "pinion"; };
  const bool cracked = in.crack.gear != FaultyGear::kNone && in.crack.depth > 0.0;
  const bool spalled = in.spall.gear != FaultyGear::kNone && in.spall.length > 0.0 && in.spall.width > 0.0;
  if ((cracked || spalled) && in.mesh_stiffness != MeshStiffnessModel::kPotentialEnergy) {
    e << "gear_pair." << (cracked ? "crack_depth = " : "spall_length = ")
      << (cracked ? in.crack.depth : in.spall.length)
      << " m needs gear_pair.mesh_stiffness = potential_energy (the square wave has no tooth geometry)";
    flush();
  }
  if (in.crack.gear != FaultyGear::kNone && in.crack.tooth >= teeth(in.crack.gear)) {
    e << "gear_pair.crack_tooth = " << in.crack.tooth << " is out of range; allowed [0, "
      << teeth(in.crack.gear) - 1 << "] (the " << gear_name(in.crack.gear) << "'s teeth)";
    flush();
  }
  if (in.spall.gear != FaultyGear::kNone && in.spall.tooth >= teeth(in.spall.gear)) {
    e << "gear_pair.spall_tooth = " << in.spall.tooth << " is out of range; allowed [0, "
      << teeth(in.spall.gear) - 1 << "] (the " << gear_name(in.spall.gear) << "'s teeth)";
    flush();
  }
  if (cracked) {
    // The crack may reach the tooth's centre line, not beyond (the model of Wu et al. and Chaari et
    // al. keeps the sections whole on the far side): its reach across the tooth stays below half the
    // tooth's thickness at the base circle.
    const bool wheel = in.crack.gear == FaultyGear::kWheel;
    const double rb = wheel ? g.base_radius2 : g.base_radius1;
    const double x = wheel ? in.profile_shift2 : in.profile_shift1;
    const double z = teeth(in.crack.gear);
    const double half = rb * std::sin(kPi / (2.0 * z) + 2.0 * x * std::tan(in.pressure_angle) / z +
                                      std::tan(in.pressure_angle) - in.pressure_angle);
    if (!(in.crack.depth * std::sin(in.crack.angle) < half)) {
      e << "gear_pair.crack_depth = " << in.crack.depth << " m is out of range at crack_angle = " << in.crack.angle
        << " rad; allowed depth sin(angle) < " << half << " m (to the tooth's centre line at its base circle)";
      flush();
    }
  }
  if (spalled) {
    const bool wheel = in.spall.gear == FaultyGear::kWheel;
    const double rb = wheel ? g.base_radius2 : g.base_radius1;
    // The contact on that tooth runs from the start of its active profile to its tip.
    const double x_lo = wheel ? g.line_of_centres_length - g.x_e : g.x_a;
    const double r_lo = std::sqrt(rb * rb + x_lo * x_lo), r_hi = wheel ? g.tip_radius2 : g.tip_radius1;
    if (!(in.spall.position >= r_lo && in.spall.position <= r_hi)) {
      e << "gear_pair.spall_position = " << in.spall.position << " m is out of range; allowed [" << r_lo << ", "
        << r_hi << "] m (the " << gear_name(in.spall.gear) << "'s active profile)";
      flush();
    }
    if (in.spall.width > in.face_width) {
      e << "gear_pair.spall_width = " << in.spall.width << " m is out of range; allowed [0, face_width = "
        << in.face_width << "] m";
      flush();
    }
  }
  for (int k = 0; k < 2; ++k) {
    const double bore = k ? in.bore_radius2 : in.bore_radius1, root = k ? g.root_radius2 : g.root_radius1;
    if (!(bore < root)) {
      e << "gear_pair.bore_radius" << k + 1 << " = " << bore << " m is out of range; allowed (0, " << root
        << ") m (below the root radius)";
      flush();
    }
  }
  const std::size_t z1 = static_cast<std::size_t>(in.pinion_teeth), z2 = static_cast<std::size_t>(in.gear_teeth);
  if (c.profile_errors.pinion.size() > z1) {
    e << "gear_pair.pinion_profile_errors has " << c.profile_errors.pinion.size() << " values; allowed at most "
      << z1 << " (pinion_teeth)";
    flush();
  }
  if (c.profile_errors.wheel.size() > z2) {
    e << "gear_pair.wheel_profile_errors has " << c.profile_errors.wheel.size() << " values; allowed at most "
      << z2 << " (gear_teeth)";
    flush();
  }
}

// GearInputs::profile_errors: the lists plus the seed's normal error per tooth (pinion teeth are
// normals 0 ... Z1 - 1 of the profile-error stream, wheel teeth the Z2 after them).
ProfileErrors resolve_profile_errors(const ModelConfig& c) {
  ProfileErrors out{c.profile_errors.pinion, c.profile_errors.wheel};
  if (c.profile_errors.sd == 0.0) return out;
  const NormalStream stream(c.seed, kProfileErrorStream);
  const auto add = [&](std::vector<double>& list, int teeth, std::uint64_t first) {
    list.resize(static_cast<std::size_t>(teeth), 0.0);
    for (int i = 0; i < teeth; ++i) list[i] += c.profile_errors.sd * stream.at(first + i);
  };
  add(out.pinion, c.gear.pinion_teeth, 0);
  add(out.wheel, c.gear.gear_teeth, static_cast<std::uint64_t>(c.gear.pinion_teeth));
  return out;
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
  validate_mesh(c, g, errors);
  if (errors.empty()) warn_friction_law(g);
  const double h = c.run.time_step;
  if (errors.empty() && is_paper_mesh(c.gear)) {
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
  } else if (errors.empty()) {
    const std::shared_ptr<const MeshTable> table = shared_mesh_table(g);
    const double q_max = g.q3 + kMaxFrictionCoefficient * std::max(table->max_friction(), 0.0);
    const double wh = std::sqrt(q_max * table->max_stiffness()) * h;
    if (!(wh < kMaxOmegaTimesStep)) {
      e << "run.time_step = " << h << " s is too large for the stiffest contact: omega_max h = " << wh
        << " with omega_max = " << wh / h << " rad/s (largest mesh stiffness " << table->max_stiffness()
        << " N/m, mu = " << kMaxFrictionCoefficient << "); RK4 needs omega_max h < " << kMaxOmegaTimesStep
        << ", i.e. time_step < " << kMaxOmegaTimesStep / (wh / h) << " s";
      errors.push_back(e.str());
      e.str("");
    }
    if (c.gear.pinion_speed * h >= table->min_piece()) {
      e << "run.time_step = " << h << " s spans the shortest interval of the mesh (" << table->min_piece()
        << " rad: a pair entering or leaving, a spall's edge or the pitch point) at pinion_speed = "
        << c.gear.pinion_speed << " rad/s; allowed time_step < " << table->min_piece() / c.gear.pinion_speed << " s";
      errors.push_back(e.str());
      e.str("");
    }
  }
  if (errors.empty() && c.gear.model == GearModel::kBearings) {
    // The bearings add modes above the contact's: the highest of the pair in contact decides.
    const double K = is_paper_mesh(c.gear) ? std::max(g.k1, g.k2) : shared_mesh_table(g)->max_stiffness();
    const double wh = bearings_max_frequency(g, K, kMaxFrictionCoefficient) * h;
    if (!(wh < kMaxOmegaTimesStep)) {
      e << "run.time_step = " << h << " s is too large for the bearings model: omega_max h = " << wh
        << " with omega_max = " << wh / h << " rad/s (gear_pair.bearing_stiffness = " << c.gear.bearing_stiffness
        << " N/m); RK4 needs omega_max h < " << kMaxOmegaTimesStep << ", i.e. time_step < "
        << kMaxOmegaTimesStep / (wh / h) << " s";
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
  c.gear.profile_errors = resolve_profile_errors(c);
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
