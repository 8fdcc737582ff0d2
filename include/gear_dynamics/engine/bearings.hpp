// The gear pair on its bearings (doc/model.md §11): the torsional coordinate of the one-degree-of-
// freedom model plus the translations of pinion and wheel on isotropic bearings, x across the line
// of action (LOA) and y along it. The mesh deflection is delta_m = delta_t + y_p - y_g; the friction
// force of the pairs in contact acts along x, on the two bodies in opposite senses. A model of the
// engine's seam (model_step.hpp): the stepping is the generic located RK4, in src/engine/bearings.cpp;
// Ensemble's lanes take the same steps in SIMD (src/engine/dispatched/bearings_step.cpp).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/model_step.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"
#include "gear_dynamics/engine/realization.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics {

// What the bearings add to a GearPair: the masses and the bearings' stiffness and damping.
struct BearingParameters {
  double pinion_mass, wheel_mass;          // m_p, m_g [kg]: the keys, or solid discs rho pi r^2 L
  double stiffness;                        // k_b [N/m], each body and direction
  double pinion_damping, wheel_damping;    // c = 2 zeta_b sqrt(k_b m) [N s/m]
};
BearingParameters bearing_parameters(const GearPair& gear);

// The highest natural frequency of the pair in contact at mesh stiffness K, undamped, with the
// torsional coordinate's Q = q3 + mu max|f| [rad/s]: what bounds RK4's step.
double bearings_max_frequency(const GearPair& gear, double stiffness, double mu);

class BearingsModel {
 public:
  static constexpr int kStates = 10;
  using State = Eigen::Matrix<double, kStates, 1>;
  // The components of the state, in order: torsional deflection and rate, then per body x, x_dot,
  // y, y_dot (pinion first).
  enum Index { kDelta = 0, kDeltaDot, kPinionX, kPinionXDot, kPinionY, kPinionYDot, kWheelX, kWheelXDot,
               kWheelY, kWheelYDot };

  explicit BearingsModel(const GearPair& gear);

  // delta_m = delta_t + y_p - y_g and its rate.
  double deflection(const State& y) const { return y[kDelta] + y[kPinionY] - y[kWheelY]; }
  double deflection_rate(const State& y) const { return y[kDeltaDot] + y[kPinionYDot] - y[kWheelYDot]; }
  // The mesh force F_m = K g + alpha |g| (delta_m_dot - e_dot) on `branch` (0 when apart) [N].
  double mesh_force(int branch, const State& y, const model_step::MeshPoint& p) const {
    if (branch == 0) return 0.0;
    const double g = (deflection(y) - p.error) - (branch > 0 ? b_ : -b_);
    return std::fma(alpha_ * (branch > 0 ? g : -g), deflection_rate(y) - p.error_rate, p.stiffness * g);
  }
  State derivative(int branch, const State& y, const model_step::MeshPoint& p) const {
    const double F = mesh_force(branch, y, p);
    const double friction = p.friction_force * F;  // on the pinion along +x, on the wheel along -x
    State dy;
    dy[kDelta] = y[kDeltaDot];
    dy[kDeltaDot] = std::fma(-p.q, F, p.load);
    dy[kPinionX] = y[kPinionXDot];
    dy[kPinionXDot] = (friction - k_ * y[kPinionX] - cp_ * y[kPinionXDot]) * inv_mp_;
    dy[kPinionY] = y[kPinionYDot];
    dy[kPinionYDot] = (-F - k_ * y[kPinionY] - cp_ * y[kPinionYDot]) * inv_mp_;
    dy[kWheelX] = y[kWheelXDot];
    dy[kWheelXDot] = (-friction - k_ * y[kWheelX] - cg_ * y[kWheelXDot]) * inv_mg_;
    dy[kWheelY] = y[kWheelYDot];
    dy[kWheelYDot] = (F - k_ * y[kWheelY] - cg_ * y[kWheelYDot]) * inv_mg_;
    return dy;
  }

  // derivative() on a packet of lanes (P an Eigen array, one lane per realization; y and dy hold
  // kStates packets, component by component): each lane computes derivative()'s expressions in
  // derivative()'s order, so its bits are the scalar path's (the ensemble's SIMD kernel,
  // src/engine/dispatched/bearings_step.cpp). side is the lane's branch (-1, 0, +1), contact its
  // magnitude; the mesh point's K, e and e_dot are the same for every lane.
  template <class P>
  struct LanePoint {
    double stiffness;
    P q, friction_force, load;
    double error, error_rate;
  };
  template <class P>
  void derivative(const P& side, const P& contact, const P* y, const LanePoint<P>& p, P* dy) const {
    const P g = P(P((y[kDelta] + y[kPinionY]) - y[kWheelY]) - p.error) - side * b_;
    const P rate = (y[kDeltaDot] + y[kPinionYDot]) - y[kWheelYDot];
    // Apart (contact 0) the force is +0, as derivative()'s 0.0: a finite product with 0 is +-0, and
    // adding +0 makes it +0; in contact F * 1 + 0 is F (F is never -0 there).
    const P F = P(kernel::fused_mul_add(P(alpha_ * P(side * g)), P(rate - p.error_rate), P(p.stiffness * g)) *
                  contact) + 0.0;
    const P friction = p.friction_force * F;
    dy[kDelta] = y[kDeltaDot];
    dy[kDeltaDot] = kernel::fused_neg_mul_add(p.q, F, p.load);
    dy[kPinionX] = y[kPinionXDot];
    dy[kPinionXDot] = ((friction - k_ * y[kPinionX]) - cp_ * y[kPinionXDot]) * inv_mp_;
    dy[kPinionY] = y[kPinionYDot];
    dy[kPinionYDot] = ((-F - k_ * y[kPinionY]) - cp_ * y[kPinionYDot]) * inv_mp_;
    dy[kWheelX] = y[kWheelXDot];
    dy[kWheelXDot] = ((-friction - k_ * y[kWheelX]) - cg_ * y[kWheelXDot]) * inv_mg_;
    dy[kWheelY] = y[kWheelYDot];
    dy[kWheelYDot] = ((F - k_ * y[kWheelY]) - cg_ * y[kWheelYDot]) * inv_mg_;
  }

  // d derivative / d y on `branch` (the tangent flow's matrix, doc/nonlinear-dynamics.md §4).
  using Jacobian = Eigen::Matrix<double, kStates, kStates>;
  Jacobian jacobian(int branch, const State& y, const model_step::MeshPoint& p) const {
    State dF = State::Zero();  // d F_m / d y
    if (branch != 0) {
      const double side = branch > 0 ? 1.0 : -1.0;
      const double g = (deflection(y) - p.error) - side * b_;
      const double by_deflection = p.stiffness + alpha_ * side * (deflection_rate(y) - p.error_rate);
      const double by_rate = alpha_ * side * g;
      dF[kDelta] = dF[kPinionY] = by_deflection;
      dF[kWheelY] = -by_deflection;
      dF[kDeltaDot] = dF[kPinionYDot] = by_rate;
      dF[kWheelYDot] = -by_rate;
    }
    Jacobian J = Jacobian::Zero();
    for (int c : {kDelta, kPinionX, kPinionY, kWheelX, kWheelY}) J(c, c + 1) = 1.0;
    J.row(kDeltaDot) = -p.q * dF.transpose();
    J.row(kPinionXDot) = p.friction_force * inv_mp_ * dF.transpose();
    J.row(kPinionYDot) = -inv_mp_ * dF.transpose();
    J.row(kWheelXDot) = -p.friction_force * inv_mg_ * dF.transpose();
    J.row(kWheelYDot) = inv_mg_ * dF.transpose();
    for (auto [u, c, inv_m] : {std::tuple{kPinionX, cp_, inv_mp_}, std::tuple{kPinionY, cp_, inv_mp_},
                               std::tuple{kWheelX, cg_, inv_mg_}, std::tuple{kWheelY, cg_, inv_mg_}}) {
      J(u + 1, u) -= k_ * inv_m;
      J(u + 1, u + 1) -= c * inv_m;
    }
    return J;
  }

  const BearingParameters& bearings() const { return p_; }
  double backlash() const { return b_; }

 private:
  BearingParameters p_;
  double b_, alpha_, k_, cp_, cg_, inv_mp_, inv_mg_;
};

// sigma = sum_j s_j lambda_j at the unwrapped pinion angle a: the friction force across the LOA per
// unit mu F_m. 1 for the paper's constant friction (D5: mu times the whole mesh force); with
// friction_direction reversing, each pair's load share with the sign of its sliding velocity
// (+1 beyond the pitch point). `table` is the schedule's (null on the paper's mesh); on the
// potential-energy mesh sigma is its interpolated column (MeshTable::Values::share).
double friction_share(const GearPair& gear, const MeshTable* table, double a);

// The outputs of one state (doc/model.md §11), SI.
struct BearingsOutputs {
  double delta_m, delta_m_dot;  // mesh deflection [m] and its rate [m/s]
  double delta_t;               // the torsional coordinate [m]
  double mesh_force;            // F_m [N]
  // What each body's bearing carries: k_b u + c u_dot along x (across the LOA) and y (along it),
  // the force the body exerts on the housing [N].
  double pinion_fx, pinion_fy, wheel_fx, wheel_fy;
};

// The mean and the root mean square of a force over the analysis window [T - W, T] [N].
struct ForceStatistics {
  double mean = 0.0, rms = 0.0;
};

// The bearings model's forces over the window (doc/model.md §11's outputs): the mesh force and what
// each body puts on its bearing across the line of action (x) and along it (y).
struct BearingForces {
  ForceStatistics mesh_force, pinion_fx, pinion_fy, wheel_fx, wheel_fy;
};

// One output of the bearings model beyond delta = delta_m and delta_dot = delta_m_dot, which every
// model has. The one list gear_run's CSV columns, gear_analyze --output, the report's force rows
// and the Python dict follow (doc/architecture.md, "Adding an output").
struct BearingsOutputSpec {
  const char* name;                        // the CSV column, the dict key, the --output value
  const char* unit;                        // SI
  double BearingsOutputs::*value;
  ForceStatistics BearingForces::*window;  // a force's window statistics (RunResult); null otherwise
};
inline constexpr BearingsOutputSpec kBearingsOutputs[] = {
    {"delta_t", "m", &BearingsOutputs::delta_t, nullptr},
    {"mesh_force", "N", &BearingsOutputs::mesh_force, &BearingForces::mesh_force},
    {"pinion_fx", "N", &BearingsOutputs::pinion_fx, &BearingForces::pinion_fx},
    {"pinion_fy", "N", &BearingsOutputs::pinion_fy, &BearingForces::pinion_fy},
    {"wheel_fx", "N", &BearingsOutputs::wheel_fx, &BearingForces::wheel_fx},
    {"wheel_fy", "N", &BearingsOutputs::wheel_fy, &BearingForces::wheel_fy},
};
// The entries of kBearingsOutputs with window statistics (the forces), in the table's order.
std::vector<BearingsOutputSpec> bearing_force_outputs();
// The entry named `name`, or null.
const BearingsOutputSpec* find_bearings_output(const std::string& name);

// The sums of the forces (bearing_force_outputs()) and of their squares over the grid points of the
// analysis window, per lane: simulate()'s RunResult::bearings and the live node's bearing_summary,
// so that both take the same sums in the same order.
class BearingForceSums {
 public:
  explicit BearingForceSums(int lanes = 1);
  // One grid point of every lane: outputs(i) gives lane i's BearingsOutputs.
  template <class Outputs>
  void observe(Outputs&& outputs) {
    for (Eigen::Index i = 0; i < sum_.cols(); ++i) {
      const BearingsOutputs o = outputs(static_cast<int>(i));
      for (std::size_t k = 0; k < forces_.size(); ++k) {
        const double f = o.*forces_[k].value;
        sum_(static_cast<Eigen::Index>(k), i) += f;
        square_(static_cast<Eigen::Index>(k), i) += f * f;
      }
    }
    ++count_;
  }
  // The mean and RMS of lane `lane`'s forces over the points observed (at least one).
  BearingForces result(int lane = 0) const;
  std::int64_t count() const { return count_; }
  void clear();

 private:
  std::vector<BearingsOutputSpec> forces_;
  Eigen::ArrayXXd sum_, square_;
  std::int64_t count_ = 0;
};

// Grid step n of one realization of the bearings model from y, with friction coefficient mu and the
// load going from load0 to load1: the located segments of mesh.plan(n) (model_step::located_segment).
// BearingsRealization's step; Ensemble's SIMD lanes give its bits. Returns the
// crossings of delta_m through +-b (+ e) located.
int bearings_step(const BearingsModel& model, const GearPair& gear, const MeshSchedule& mesh, double time_step,
                  double mu, std::int64_t n, double load0, double load1, BearingsModel::State& y);

// bearings_step for any model of the seam whose mesh is the bearings model's (its MeshPoints): the
// bearings model itself, or one that carries more along its state (the tangent flow,
// dynamics/lyapunov.cpp), stepped through the same located segments.
template <class M>
int bearings_step_of(const M& model, const GearPair& gear, const MeshSchedule& mesh, double h, double mu,
                     std::int64_t n, double load0, double load1, typename M::State& y) {
  const StepPlan plan = mesh.plan(n);
  const double q3 = gear.q3;
  const double speed = gear.in.pinion_speed, a_start = gear.in.mesh_phase + speed * static_cast<double>(n) * h;
  const MeshTable* table = mesh.table();
  int crossings = 0;
  for (int k = 0; k < plan.segments; ++k) {
    const StepSegment& seg = plan.segment[k];
    const double H = (seg.end - seg.begin) * h;
    const kernel::SegmentLoads<double> l = kernel::segment_loads<double>(seg, q3, mu, load0, load1);
    // sigma at the stage times, a billionth of the segment inside it (its side of a jump).
    const double inset = 1e-9 * (seg.end - seg.begin);
    const auto share = [&](double u) {
      return mu == 0.0 ? 0.0 : mu * friction_share(gear, table, a_start + speed * h * u);
    };
    const double e_dot = (seg.error_end - seg.error_start) / H;
    const double mid = 0.5 * (seg.begin + seg.end);
    model_step::Segment s{H,
                          gear.in.backlash,
                          {seg.stiffness_start, l.qa, share(seg.begin + inset), l.la, seg.error_start, e_dot},
                          {seg.stiffness_mid, l.qm, share(mid), 0.5 * (l.la + l.lb),
                           0.5 * (seg.error_start + seg.error_end), e_dot},
                          {seg.stiffness_end, l.qb, share(seg.end - inset), l.lb, seg.error_end, e_dot}};
    crossings += model_step::located_segment(model, s, y);
  }
  return crossings;
}

// The outputs of state y at grid step n (doc/model.md §11).
BearingsOutputs bearings_outputs(const BearingsModel& model, const GearPair& gear, const MeshSchedule& mesh,
                                 double time_step, std::int64_t n, const BearingsModel::State& y);
// The schedule's K, e and e's rate at time t, what the outputs read of the mesh (the point's other
// fields unused): looked up once per instant for all the lanes of an ensemble.
model_step::MeshPoint output_mesh_point(const MeshSchedule& mesh, double t);
// The same with the mesh at y's time given (output_mesh_point).
BearingsOutputs bearings_outputs(const BearingsModel& model, const GearPair& gear,
                                 const model_step::MeshPoint& mesh_point, const BearingsModel::State& y);
// The same for lane i of an ensemble of the bearings model (Ensemble::model_state()) at its time,
// `mesh_point` = output_mesh_point(ensemble.mesh(), ensemble.time()).
BearingsOutputs bearings_outputs(const Ensemble& ensemble, const model_step::MeshPoint& mesh_point, int lane);
// The error a bearings realization's non-finite state throws.
DivergenceError bearings_divergence(std::uint64_t realization, int lane, double delta_m, double time);

// One realization of the bearings model, as Realization is one of the torsional model (the
// interface of RealizationBase): the same mesh plan, the same random stream NormalStream(seed,
// realization) and load increments, so that Phi's path is the torsional run's, bit for bit; and the
// same stepping as Ensemble's bearings lanes, so its path is theirs, bit for bit.
class BearingsRealization : public RealizationBase {
 public:
  using State = BearingsModel::State;

  BearingsRealization(const GearPair& gear, double time_step, const InitialState& initial, const LaneSpec& lane,
                      std::uint64_t seed);

  // Advances by one grid step. Throws DivergenceError on a non-finite state.
  void step();
  void reset();

  const BearingsModel& model() const { return model_; }
  const State& state() const { return y_; }
  void set_state(const State& y) { y_ = y; }
  // Crossings of delta_m through +-b (+ e) located so far.
  std::int64_t crossings() const { return crossings_; }
  BearingsOutputs outputs() const { return bearings_outputs(model_, gear_, mesh_, h_, n_, y_); }

  // The located segments of grid step n from state y with loads load0 -> load1 (bearings_step; public
  // for the tests of the seam).
  int advance(std::int64_t n, double load0, double load1, State& y) const {
    return bearings_step(model_, gear_, mesh_, h_, spec_.mu, n, load0, load1, y);
  }

 private:
  BearingsModel model_;
  std::int64_t crossings_ = 0;
  State y_ = State::Zero();
};

}  // namespace gear_dynamics
