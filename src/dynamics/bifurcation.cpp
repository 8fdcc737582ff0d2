#include "gear_dynamics/dynamics/bifurcation.hpp"

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace gear_dynamics {

ScanParameter parse_scan_parameter(const std::string& n) {
  if (n == "speed") return ScanParameter::Speed;
  if (n == "load") return ScanParameter::Load;
  if (n == "mu") return ScanParameter::Friction;
  if (n == "damping") return ScanParameter::Damping;
  throw std::invalid_argument("unknown scan parameter '" + n + "' (speed, load, mu, damping)");
}

std::string scan_parameter_name(ScanParameter p) {
  switch (p) {
    case ScanParameter::Speed: return "speed";
    case ScanParameter::Load: return "load";
    case ScanParameter::Friction: return "mu";
    case ScanParameter::Damping: return "damping";
  }
  return "?";
}

ModelConfig with_parameter(const ModelConfig& base, ScanParameter p, double v) {
  ModelConfig c = base;
  switch (p) {
    case ScanParameter::Speed: c.gear.pinion_speed = v * 2.0 * M_PI / 60.0; break;
    case ScanParameter::Load: c.load.initial_mean = v; break;
    case ScanParameter::Friction: c.friction_coefficient = v; break;
    case ScanParameter::Damping: c.gear.damping_ratio = v; break;
  }
  return c;
}

int period_search_limit(const GearInputs& gear, int at_least) {
  return std::max(at_least, schedule_mesh_periods(gear));
}

int detect_period(const std::vector<SectionState>& pts, int max_period, const std::vector<double>& tol) {
  const int n = static_cast<int>(pts.size());
  for (int p = 1; p <= max_period && 2 * p <= n; ++p) {
    bool ok = true;
    for (int k = 0; k + p < n && ok; ++k)
      for (std::size_t c = 0; c < tol.size() && ok; ++c)
        ok = std::abs(pts[k + p].x[c] - pts[k].x[c]) <= tol[c];
    if (ok) return p;
  }
  return 0;
}

namespace {

// The period is tested on the whole state: every displacement within tolerance * b, every rate
// within tolerance * v_ref (the state's components alternate displacement, rate).
void classify(ScanValue& v, const ScanOptions& o, const GearInputs& gear, double b, double vref) {
  std::vector<double> tolerance;
  for (std::size_t c = 0; c < (v.points.empty() ? 2 : v.points.front().x.size()); ++c)
    tolerance.push_back(o.tolerance * (c % 2 == 0 ? b : vref));
  v.period = detect_period(v.points, period_search_limit(gear, o.max_period), tolerance);
  const std::string motion = v.period > 0 ? "period-" + std::to_string(v.period) : "aperiodic";
  if (v.min_gap > 0) v.regime = motion + ", no separation";
  else if (v.min_delta >= -b) v.regime = motion + ", single-sided impacts";
  else v.regime = motion + ", double-sided impacts";
}

// One value of a scan of the bearings model: a lane of the engine's ensemble with its whole state
// sampled (BearingsLanes); min_delta is that of the mesh deflection delta_m.
std::vector<SectionState> bearings_section(const ModelConfig& c, const ScanOptions& o, double& min_delta) {
  Ensemble e(derive(c.gear), c.run.time_step, c.initial, {deterministic_lane(c, c.friction_coefficient)}, c.seed);
  BearingsLanes sys(e);
  const BearingsModel& model = *e.bearings_model();
  const std::int64_t n_start = std::llround(o.transient / c.run.time_step);
  min_delta = std::numeric_limits<double>::infinity();
  const auto track = [&](const LaneSystem&) {
    if (e.step_index() < n_start) return;
    const BearingsModel::State y = e.model_state().col(0);
    min_delta = std::min(min_delta, model.deflection(y));
  };
  return poincare_section(sys, {mesh_period(e.gear()), 0.0, o.transient, o.duration, {}}, track);
}

// The bearings model's points as the scan reports them: (delta_m, delta_m_dot).
void to_mesh_deflection(std::vector<SectionState>& points, const BearingsModel& model) {
  for (SectionState& p : points) {
    const BearingsModel::State y = Eigen::Map<const BearingsModel::State>(p.x.data());
    p.x = {model.deflection(y), model.deflection_rate(y)};
  }
}

}  // namespace

std::vector<ScanValue> bifurcation_scan(const ModelConfig& base, ScanParameter param, const std::vector<double>& values,
                                        const ScanOptions& o) {
  const double h = base.run.time_step;
  std::vector<ModelConfig> configs;
  for (double v : values) {
    ModelConfig c = with_parameter(base, param, v);
    validate_consistency(c);
    configs.push_back(c);
  }
  std::vector<ScanValue> out(values.size());
  if (base.gear.model == GearModel::kBearings) {
    tbb::parallel_for(std::size_t(0), values.size(), [&](std::size_t i) {
      ScanValue& v = out[i];
      v.value = values[i];
      v.points = bearings_section(configs[i], o, v.min_delta);
      const double b = configs[i].gear.backlash;
      v.min_gap = v.min_delta - b;
      classify(v, o, configs[i].gear, b, std::sqrt(2.0 * std::abs(configs[i].load.initial_mean) * b));
      to_mesh_deflection(v.points, BearingsModel(derive(configs[i].gear)));
      for (SectionState& p : v.points) p.lane = 0;
    });
    return out;
  }
  const bool shared = param == ScanParameter::Load || param == ScanParameter::Friction;
  const int per_block = std::max(1, o.block_lanes);
  const std::size_t blocks = (values.size() + per_block - 1) / per_block;

  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t blk) {
    const std::size_t first = blk * per_block, last = std::min(values.size(), first + per_block);
    const GearPair gear = derive(configs[first].gear);
    PoincareOptions po;
    po.period = mesh_period(gear);
    for (std::size_t i = first; i < last; ++i) po.lane_period.push_back(mesh_period(derive(configs[i].gear)));
    po.offset = 0;
    po.start = o.transient;
    po.end = o.duration;
    const int nl = static_cast<int>(last - first);
    std::vector<double> min_gap(nl, std::numeric_limits<double>::infinity()), min_delta = min_gap;
    const std::int64_t n_start = std::llround(o.transient / h);
    const auto track = [&](const LaneSystem& s) {
      if (s.step_index() < n_start) return;
      for (int l = 0; l < nl; ++l) {
        const double d = s.state(l, 0);
        min_delta[l] = std::min(min_delta[l], d);
      }
    };
    std::vector<SectionState> pts;
    if (shared) {
      std::vector<LaneSpec> lanes;
      for (std::size_t i = first; i < last; ++i) {
        const ModelConfig& c = configs[i];
        LaneSpec s = deterministic_lane(c, c.friction_coefficient);
        lanes.push_back(s);
      }
      Ensemble e(gear, h, configs[first].initial, lanes, configs[first].seed);
      EnsembleLanes sys(e);
      pts = poincare_section(sys, po, track);
    } else {
      std::vector<GearLaneSpec> lanes;
      for (std::size_t i = first; i < last; ++i) {
        const ModelConfig& c = configs[i];
        lanes.push_back(GearLaneSpec{c.gear, c.friction_coefficient, c.load.initial_mean, c.initial});
      }
      GearLanes sys(lanes, h);
      pts = poincare_section(sys, po, track);
    }
    const double b = gear.in.backlash;
    for (int l = 0; l < nl; ++l) {
      ScanValue& v = out[first + l];
      v.value = values[first + l];
      for (const SectionState& p : pts)
        if (p.lane == l) {
          v.points.push_back(p);
          v.points.back().lane = 0;
        }
      v.min_delta = min_delta[l];
      v.min_gap = min_delta[l] - b;
      classify(v, o, configs[first + l].gear, b, std::sqrt(2.0 * std::abs(configs[first + l].load.initial_mean) * b));
    }
  });
  return out;
}

}  // namespace gear_dynamics
