// A generic deterministic system stepped on a fixed grid, many trajectories ("lanes") at once: the
// one interface behind the Poincare sections, the bifurcation scans and the Lyapunov exponents
// (doc/nonlinear-dynamics.md §1). Implementations: the gear model through the production Ensemble
// (EnsembleLanes: lanes share the mesh schedule, differ in load and mu), the gear model with a mesh
// schedule per lane (GearLanes: speed, mesh phase and damping per lane, same arithmetic as the
// Ensemble, bit for bit), a forced linear damped oscillator and the Lorenz system (analytic checks).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics {

class LaneSystem {
 public:
  virtual ~LaneSystem() = default;
  virtual int dimension() const = 0;  // state components per lane
  virtual int lanes() const = 0;
  virtual double time_step() const = 0;
  virtual std::int64_t step_index() const = 0;
  double time() const { return static_cast<double>(step_index()) * time_step(); }
  // Advances every lane by one grid step.
  virtual void step() = 0;
  virtual double state(int lane, int component) const = 0;
  // Overwrites one lane's state at the current step (x has dimension() values).
  virtual void set_state(int lane, const double* x) = 0;
  // For a second-order system: the component that is the time derivative of `component`, or -1.
  // Poincare sampling between grid points uses it for cubic Hermite interpolation.
  virtual int derivative_of(int component) const { (void)component; return -1; }
};

// --- the gear model (state: delta [m], delta_dot [m/s]; the load is constant per lane) ---

// The bearings model's lanes of an Ensemble (gear_pair.model = bearings) with their whole state,
// BearingsModel::State's ten components: the largest Lyapunov exponent of the full state.
class BearingsLanes : public LaneSystem {
 public:
  explicit BearingsLanes(Ensemble& ensemble);  // throws unless the ensemble runs the bearings model
  int dimension() const override;
  int lanes() const override { return e_.lanes(); }
  double time_step() const override { return e_.time_step(); }
  std::int64_t step_index() const override { return e_.step_index(); }
  void step() override { e_.step(); }
  double state(int lane, int c) const override { return e_.model_state()(c, lane); }
  void set_state(int lane, const double* x) override { e_.set_model_state(lane, x); }
  int derivative_of(int c) const override;

 private:
  Ensemble& e_;
};

// The production engine as a LaneSystem. Only deterministic lanes (LaneSpec::stochastic = false)
// make a deterministic system; stochastic lanes step too but are not meant for Lyapunov exponents.
class EnsembleLanes : public LaneSystem {
 public:
  explicit EnsembleLanes(Ensemble& ensemble) : e_(ensemble) {}
  int dimension() const override { return 2; }
  int lanes() const override { return e_.lanes(); }
  double time_step() const override { return e_.time_step(); }
  std::int64_t step_index() const override { return e_.step_index(); }
  void step() override { e_.step(); }
  double state(int lane, int c) const override { return c == 0 ? e_.delta()[lane] : e_.velocity()[lane]; }
  void set_state(int lane, const double* x) override { e_.set_state(lane, x[0], x[1]); }
  int derivative_of(int c) const override { return c == 0 ? 1 : -1; }
  Ensemble& ensemble() { return e_; }

 private:
  Ensemble& e_;
};

// One deterministic gear lane with its own gear inputs (speed, mesh phase, damping ratio ...).
struct GearLaneSpec {
  GearInputs gear;
  double mu = 0.0;       // friction coefficient [-]
  double load = 20.0;    // Phi, constant [m/s^2]
  InitialState initial;  // delta(0), delta_dot(0)
};

// Deterministic gear lanes, each with its own mesh schedule, stepped one by one with exactly the
// arithmetic of Ensemble::step() for a lane with sigma = drift = 0 (GearLanes.BitIdenticalToEnsemble checks bit
// identity). For scans over what the Ensemble's lanes share: speed, mesh phase, damping.
class GearLanes : public LaneSystem {
 public:
  GearLanes(const std::vector<GearLaneSpec>& lanes, double time_step);
  int dimension() const override { return 2; }
  int lanes() const override { return static_cast<int>(lane_.size()); }
  double time_step() const override { return h_; }
  std::int64_t step_index() const override { return n_; }
  void step() override;
  double state(int lane, int c) const override { return c == 0 ? d_[lane] : v_[lane]; }
  void set_state(int lane, const double* x) override { d_[lane] = x[0]; v_[lane] = x[1]; }
  int derivative_of(int c) const override { return c == 0 ? 1 : -1; }
  const GearPair& gear(int lane) const { return lane_[lane].gear; }
  const MeshSchedule& mesh(int lane) const { return lane_[lane].mesh; }
  double load(int lane) const { return load_[lane]; }
  double mu(int lane) const { return mu_[lane]; }

 private:
  struct Lane {
    GearPair gear;
    MeshSchedule mesh;
  };
  void step_lane(int i, const StepPlan& plan);
  std::vector<Lane> lane_;
  // Structure of arrays, padded to a multiple of Ensemble::kPacket lanes (padding lanes stay 0).
  Eigen::ArrayXd d_, v_, load_, mu_, q3_, b_, alpha_, ka_, km_, kb_, fa_, fm_, fb_, ea_, eb_;
  std::vector<StepPlan> plan_;
  double h_;
  std::int64_t n_ = 0;
};

// mesh_force (the quantity of the force spectra) is in gear_dynamics/model/gear_pair.hpp.

// --- analytic reference systems (classical RK4 on the grid) ---

// x'' + 2 zeta omega x' + omega^2 x = F cos(w t): state (x, x'); one parameter set for all lanes.
struct LinearOscillatorParams {
  double omega = 1.0, zeta = 0.05, force = 0.0, forcing_frequency = 1.0;
};
class LinearOscillatorLanes : public LaneSystem {
 public:
  LinearOscillatorLanes(const std::vector<LinearOscillatorParams>& lanes, double time_step,
                        const std::vector<double>& x0, const std::vector<double>& v0);
  int dimension() const override { return 2; }
  int lanes() const override { return static_cast<int>(p_.size()); }
  double time_step() const override { return h_; }
  std::int64_t step_index() const override { return n_; }
  void step() override;
  double state(int lane, int c) const override { return x_[2 * lane + c]; }
  void set_state(int lane, const double* x) override { x_[2 * lane] = x[0]; x_[2 * lane + 1] = x[1]; }
  int derivative_of(int c) const override { return c == 0 ? 1 : -1; }
  // The analytic steady state (x, x') at time t (particular solution).
  static void steady_state(const LinearOscillatorParams& p, double t, double& x, double& v);

 private:
  std::vector<LinearOscillatorParams> p_;
  std::vector<double> x_;
  double h_;
  std::int64_t n_ = 0;
};

// Lorenz: x' = s (y - x), y' = x (r - z) - y, z' = x y - b z.
struct LorenzParams {
  double sigma = 10.0, rho = 28.0, beta = 8.0 / 3.0;
};
class LorenzLanes : public LaneSystem {
 public:
  LorenzLanes(const LorenzParams& p, double time_step, const std::vector<std::vector<double>>& initial);
  int dimension() const override { return 3; }
  int lanes() const override { return static_cast<int>(x_.size() / 3); }
  double time_step() const override { return h_; }
  std::int64_t step_index() const override { return n_; }
  void step() override;
  double state(int lane, int c) const override { return x_[3 * lane + c]; }
  void set_state(int lane, const double* x) override {
    for (int c = 0; c < 3; ++c) x_[3 * lane + c] = x[c];
  }

 private:
  LorenzParams p_;
  std::vector<double> x_;
  double h_;
  std::int64_t n_ = 0;
};

}  // namespace gear_dynamics
