#include "gear_dynamics/ros/conversions.hpp"

#include <xmlrpcpp/XmlRpcValue.h>

#include <cmath>

#include "gear_dynamics/batch/manifest.hpp"  // package_version

namespace gear_dynamics {

namespace {

YAML::Node to_yaml(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return YAML::Node(static_cast<bool>(v));
    case XmlRpc::XmlRpcValue::TypeInt:
      return YAML::Node(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble:
      return YAML::Node(static_cast<double>(v));
    case XmlRpc::XmlRpcValue::TypeString:
      return YAML::Node(static_cast<std::string>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      YAML::Node n(YAML::NodeType::Sequence);
      for (int i = 0; i < v.size(); ++i) n.push_back(to_yaml(v[i]));
      return n;
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      YAML::Node n(YAML::NodeType::Map);
      for (auto& kv : v) n[kv.first] = to_yaml(kv.second);
      return n;
    }
    default:
      return YAML::Node();  // invalid / binary / date: reported as missing or wrong type
  }
}

}  // namespace

YAML::Node yaml_from_parameters(const ros::NodeHandle& nh, const std::vector<std::string>& sections) {
  YAML::Node root(YAML::NodeType::Map);
  for (const std::string& s : sections) {
    XmlRpc::XmlRpcValue v;
    if (nh.getParam(s, v)) root[s] = to_yaml(v);
  }
  return root;
}

YAML::Node yaml_from_namespace(const ros::NodeHandle& nh) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(nh.getNamespace(), v) || v.getType() != XmlRpc::XmlRpcValue::TypeStruct)
    return YAML::Node(YAML::NodeType::Map);
  return to_yaml(v);
}

ModelConfig load_model_config(const ros::NodeHandle& nh) {
  return parse_config(yaml_from_parameters(nh, {"gear_pair", "load", "run"}));
}

RunInfo make_run_info(const ModelConfig& config, RunKind kind, std::uint32_t realization,
                      double mu, double sigma, double duration) {
  YAML::Emitter out;
  out << to_yaml(config);
  return make_run_info(config, kind, realization, mu, sigma, duration, out.c_str());
}

RunInfo make_run_info(const ModelConfig& config, RunKind kind, std::uint32_t realization, double mu, double sigma,
                      double duration, std::string parameters_yaml) {
  RunInfo m;
  m.header.stamp = sim_stamp(0.0);
  m.package_version = package_version();
  m.kind = to_string(kind);
  m.seed = config.seed;
  m.realization = realization;
  m.mu = mu;
  m.sigma = sigma;
  m.time_step = config.run.time_step;
  m.duration = duration;
  m.mesh_phase = config.gear.mesh_phase;
  m.clock_offset = kClockOffset;
  m.parameters_yaml = std::move(parameters_yaml);
  return m;
}

GearState make_state(const Ensemble& e, int lane, double center_distance) {
  GearState m;
  const double t = e.time();
  m.t = grid_time(e.step_index(), e.time_step());
  m.header.stamp = sim_stamp(m.t);
  m.delta = e.delta()[lane];
  m.delta_dot = e.velocity()[lane];
  m.phi = e.load()[lane];
  m.center_distance = center_distance;
  m.mesh_stiffness = e.mesh().stiffness(t);
  m.mesh_phase = e.mesh().phase(t);
  m.mu = e.lane(lane).mu;
  m.sigma = e.lane(lane).sigma;
  m.realization = static_cast<std::uint32_t>(e.lane(lane).realization);
  m.seed = e.seed();
  return m;
}

GearState make_state(const LiveSample& s) {
  GearState m;
  m.header.stamp = sim_stamp(s.t);
  m.t = s.t;
  m.delta = s.delta;
  m.delta_dot = s.delta_dot;
  m.phi = s.phi;
  m.center_distance = s.center_distance;
  m.mesh_stiffness = s.mesh_stiffness;
  m.mesh_phase = s.mesh_phase;
  m.mu = s.mu;
  m.sigma = s.sigma;
  m.realization = static_cast<std::uint32_t>(s.realization);
  m.seed = s.seed;
  return m;
}

PoincarePoint make_poincare_point(const SectionPoint& p) {
  PoincarePoint m;
  m.t = p.time;
  m.delta = p.delta;
  m.delta_dot = p.delta_dot;
  m.mesh_phase = 0.0;  // the section of the batch and of gear_analyze poincare
  return m;
}

RunSummary make_summary(const std::string& run_name, RunKind kind,
                        std::uint32_t realization, double mu, double mesh_phase,
                        const RunSettings& run, const RunResult& r) {
  RunSummary m;
  m.header.stamp = sim_stamp(run.duration);
  m.run_name = run_name;
  m.kind = to_string(kind);
  m.realization = realization;
  m.mu = mu;
  m.mesh_phase = mesh_phase;
  m.center_distance = r.center_distance;
  m.delta_range = r.delta_range;
  m.delta_dot_range = r.delta_dot_range;
  m.steady_state_time = r.steady_state_time;
  m.steady_state_time_fine = r.steady_state_time_fine;
  m.reached_steady_state = r.reached_steady_state;
  m.final_delta = r.final_delta;
  m.final_delta_dot = r.final_delta_dot;
  m.final_phi = r.final_load;
  for (const SnapshotState& s : r.snapshots) {
    m.snapshot_times.push_back(s.time);
    m.snapshot_delta.push_back(s.delta);
    m.snapshot_delta_dot.push_back(s.delta_dot);
    m.snapshot_phi.push_back(s.load);
  }
  return m;
}

MeshState make_mesh_state(double t, const BearingsOutputs& o, double delta_t) {
  MeshState m;
  m.header.stamp = sim_stamp(t);
  m.t = t;
  m.delta_m = o.delta_m;
  m.delta_m_dot = o.delta_m_dot;
  m.delta_t = delta_t;
  m.mesh_force = o.mesh_force;
  return m;
}

geometry_msgs::WrenchStamped make_bearing_wrench(double t, const char* frame, double fx, double fy) {
  geometry_msgs::WrenchStamped m;
  m.header.stamp = sim_stamp(t);
  m.header.frame_id = frame;
  m.wrench.force.x = fx;
  m.wrench.force.y = fy;
  return m;
}

std::vector<geometry_msgs::TransformStamped> make_bearing_frames(const GearPair& g, const ros::Time& stamp) {
  const double alpha = g.operating_pressure_angle;
  const double centre_distance = (g.base_radius1 + g.base_radius2) / std::cos(alpha);
  const auto frame = [&](const char* child, double x) {
    geometry_msgs::TransformStamped m;
    m.header.stamp = stamp;
    m.header.frame_id = kGearPairFrame;
    m.child_frame_id = child;
    m.transform.translation.x = x;
    m.transform.rotation.z = std::sin(-0.5 * alpha);  // about z by -alpha_w
    m.transform.rotation.w = std::cos(-0.5 * alpha);
    return m;
  };
  return {frame(kPinionBearingFrame, 0.0), frame(kWheelBearingFrame, centre_distance)};
}

BearingSummary make_bearing_summary(const std::string& run_name, const RunSettings& run, const BearingForces& f) {
  return make_bearing_summary(run_name, run.duration, run.duration - run.window, f);
}

BearingSummary make_bearing_summary(const std::string& run_name, double t, double window_start,
                                    const BearingForces& f) {
  BearingSummary m;
  m.header.stamp = sim_stamp(t);
  m.run_name = run_name;
  m.window_start = window_start;
  m.mesh_force_mean = f.mesh_force.mean, m.mesh_force_rms = f.mesh_force.rms;
  m.pinion_fx_mean = f.pinion_fx.mean, m.pinion_fx_rms = f.pinion_fx.rms;
  m.pinion_fy_mean = f.pinion_fy.mean, m.pinion_fy_rms = f.pinion_fy.rms;
  m.wheel_fx_mean = f.wheel_fx.mean, m.wheel_fx_rms = f.wheel_fx.rms;
  m.wheel_fy_mean = f.wheel_fy.mean, m.wheel_fy_rms = f.wheel_fy.rms;
  return m;
}

}  // namespace gear_dynamics
