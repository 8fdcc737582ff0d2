// The bearings model (engine/bearings.hpp): its parameters, friction share, one-lane step and
// outputs. The ensemble's SIMD lanes are src/engine/dispatched/bearings_step.cpp.
#include "gear_dynamics/engine/bearings.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "gear_dynamics/engine/rk4_kernel.hpp"
#include "gear_dynamics/model/friction_law.hpp"
#include "gear_dynamics/model/mesh_table.hpp"

namespace gear_dynamics {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

BearingParameters bearing_parameters(const GearPair& gear) {
  const GearInputs& in = gear.in;
  BearingParameters p;
  const double disc = in.density * kPi * in.face_width;
  p.pinion_mass = in.pinion_mass > 0.0 ? in.pinion_mass : disc * in.pinion_pitch_radius * in.pinion_pitch_radius;
  p.wheel_mass = in.wheel_mass > 0.0 ? in.wheel_mass : disc * in.gear_pitch_radius * in.gear_pitch_radius;
  p.stiffness = in.bearing_stiffness;
  p.pinion_damping = 2.0 * in.bearing_damping_ratio * std::sqrt(p.stiffness * p.pinion_mass);
  p.wheel_damping = 2.0 * in.bearing_damping_ratio * std::sqrt(p.stiffness * p.wheel_mass);
  return p;
}

double bearings_max_frequency(const GearPair& gear, double stiffness, double mu) {
  const BearingParameters p = bearing_parameters(gear);
  // A law's f carries mu_j / mu_ref, which may exceed 1: take its table's largest then.
  const double f_max = gear.in.friction_model != FrictionModel::kConstant
                           ? std::fabs(shared_mesh_table(gear)->max_friction())
                           : std::max(std::fabs(gear.friction_factor(0.0)),
                                      std::fabs(gear.friction_factor(gear.mesh_period_angle)));
  // (delta_t, y_p, y_g): V = 1/2 K (delta_t + y_p - y_g)^2 + 1/2 k_b (y_p^2 + y_g^2); x's modes are
  // sqrt(k_b / m), below the y ones.
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero(), K;
  M.diagonal() << 1.0 / (gear.q3 + mu * f_max), p.pinion_mass, p.wheel_mass;
  const Eigen::Vector3d grad(1.0, 1.0, -1.0);
  K = stiffness * grad * grad.transpose();
  K(1, 1) += p.stiffness;
  K(2, 2) += p.stiffness;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> es(K, M, Eigen::EigenvaluesOnly);
  return std::sqrt(es.eigenvalues().maxCoeff());
}

BearingsModel::BearingsModel(const GearPair& gear)
    : p_(bearing_parameters(gear)),
      b_(gear.in.backlash),
      alpha_(gear.damping_coefficient),
      k_(p_.stiffness),
      cp_(p_.pinion_damping),
      cg_(p_.wheel_damping),
      inv_mp_(1.0 / p_.pinion_mass),
      inv_mg_(1.0 / p_.wheel_mass) {}

double friction_share(const GearPair& gear, const MeshTable* table, double a) {
  if (gear.in.friction_model == FrictionModel::kConstant && gear.in.friction_direction == FrictionDirection::kConstant)
    return 1.0;
  if (table && gear.in.mesh_stiffness == MeshStiffnessModel::kPotentialEnergy) {
    // The potential-energy model costs microseconds per exact evaluation (three per segment and
    // step): sigma is interpolated from the table, as K, f and e are.
    const double P = table->period();
    return table->at(a - std::floor(a / P) * P).share;
  }
  if (gear.in.friction_model != FrictionModel::kConstant) {
    // A law: each pair by its share and its own mu (a law's mesh always has a table).
    const double P = table->period();
    const std::vector<MeshContact> contacts = table->contacts(a - std::floor(a / P) * P);
    double total = 0.0;
    for (const MeshContact& c : contacts) total += c.stiffness;
    double share = 0.0;
    for (const MeshContact& c : contacts) share += pair_friction_weight(gear, c.x, c.x, c.stiffness / total);
    return share;
  }
  const auto sign = [&](double x) { return x >= gear.x_p ? 1.0 : -1.0; };
  // The square wave: 1 in single contact, 1/2 each in double contact.
  const double phi = a - std::floor(a / gear.mesh_period_angle) * gear.mesh_period_angle;
  const double ref = sign(gear.x_b + gear.base_radius1 * phi);
  if (phi < gear.single_pair_angle) return ref;
  return 0.5 * (ref + sign(gear.x_a + gear.base_radius1 * (phi - gear.single_pair_angle)));
}

int bearings_step(const BearingsModel& model, const GearPair& gear, const MeshSchedule& mesh, double h, double mu,
                  std::int64_t n, double load0, double load1, BearingsModel::State& y) {
  return bearings_step_of(model, gear, mesh, h, mu, n, load0, load1, y);
}

BearingsOutputs bearings_outputs(const BearingsModel& model, const GearPair& gear, const MeshSchedule& mesh,
                                 double h, std::int64_t n, const BearingsModel::State& y) {
  return bearings_outputs(model, gear, output_mesh_point(mesh, static_cast<double>(n) * h), y);
}

model_step::MeshPoint output_mesh_point(const MeshSchedule& mesh, double t) {
  // e's rate as the stepping integrates e (the table's slope), so F_m is the force of the derivative.
  return {mesh.stiffness(t), 0.0, 0.0, 0.0, mesh.transmission_error(t), mesh.transmission_error_rate(t)};
}

BearingsOutputs bearings_outputs(const BearingsModel& model, const GearPair& gear, const model_step::MeshPoint& p,
                                 const BearingsModel::State& y) {
  const double dm = model.deflection(y);
  const BearingParameters& b = model.bearings();
  using M = BearingsModel;
  return {dm,
          model.deflection_rate(y),
          y[M::kDelta],
          model.mesh_force(model_step::branch_of(dm, p.error, gear.in.backlash), y, p),
          b.stiffness * y[M::kPinionX] + b.pinion_damping * y[M::kPinionXDot],
          b.stiffness * y[M::kPinionY] + b.pinion_damping * y[M::kPinionYDot],
          b.stiffness * y[M::kWheelX] + b.wheel_damping * y[M::kWheelXDot],
          b.stiffness * y[M::kWheelY] + b.wheel_damping * y[M::kWheelYDot]};
}

std::vector<BearingsOutputSpec> bearing_force_outputs() {
  std::vector<BearingsOutputSpec> forces;
  for (const BearingsOutputSpec& o : kBearingsOutputs)
    if (o.window) forces.push_back(o);
  return forces;
}

BearingForceSums::BearingForceSums(int lanes)
    : forces_(bearing_force_outputs()),
      sum_(Eigen::ArrayXXd::Zero(static_cast<Eigen::Index>(forces_.size()), lanes)),
      square_(sum_) {}

BearingForces BearingForceSums::result(int lane) const {
  const double n = static_cast<double>(count_);
  BearingForces r;
  for (std::size_t k = 0; k < forces_.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    r.*forces_[k].window = ForceStatistics{sum_(row, lane) / n, std::sqrt(square_(row, lane) / n)};
  }
  return r;
}

void BearingForceSums::clear() {
  sum_.setZero();
  square_.setZero();
  count_ = 0;
}

const BearingsOutputSpec* find_bearings_output(const std::string& name) {
  for (const BearingsOutputSpec& o : kBearingsOutputs)
    if (name == o.name) return &o;
  return nullptr;
}

BearingsOutputs bearings_outputs(const Ensemble& ensemble, const model_step::MeshPoint& mesh_point, int lane) {
  const BearingsModel::State y = ensemble.model_state().col(lane);
  return bearings_outputs(*ensemble.bearings_model(), ensemble.gear(), mesh_point, y);
}

BearingsRealization::BearingsRealization(const GearPair& gear, double time_step, const InitialState& initial,
                                         const LaneSpec& lane, std::uint64_t seed)
    : RealizationBase(gear, time_step, initial, lane, seed), model_(gear) {
  reset();
}

void BearingsRealization::reset() {
  restart();
  crossings_ = 0;
  y_ = State::Zero();
  y_[BearingsModel::kDelta] = initial_.deflection;
  y_[BearingsModel::kDeltaDot] = initial_.velocity;
}

void BearingsRealization::step() {
  const double load1 = next_load(next_normal());
  crossings_ += advance(n_, load_, load1, y_);
  load_ = load1;
  ++n_;
  if (!y_.allFinite()) throw bearings_divergence(spec_.realization, 0, model_.deflection(y_), time());
}

DivergenceError bearings_divergence(std::uint64_t realization, int lane, double delta_m, double time) {
  std::ostringstream msg;
  msg << "gear model (bearings) diverged: realization " << realization << " (lane " << lane << ") has delta_m = "
      << delta_m << " m at t = " << time << " s";
  return DivergenceError(msg.str(), lane, realization, time);
}

}  // namespace gear_dynamics
