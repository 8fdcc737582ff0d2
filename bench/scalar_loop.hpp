// A plain scalar C++ implementation of doc/model.md §2 and §5, written apart from the engine: one
// realization at a time, one step after the other, plain doubles, its own mesh timing. It is the
// "plain C++" row of bench/run and a cross-check of the engine; it draws the same random streams
// (gear_dynamics::NormalStream), so it must agree with the engine path by path.
#pragma once

#include <cstdint>
#include <vector>

#include "gear_dynamics/engine/ensemble.hpp"  // LaneSpec
#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_bench {

struct ScalarState {
  double delta = 0.0, velocity = 0.0, load = 0.0;
};

class ScalarModel {
 public:
  // Throws std::invalid_argument if one step could hold more than one stiffness switch.
  ScalarModel(const gear_dynamics::GearPair& gear, double time_step);

  // Runs one realization from (delta0, v0) over `steps` grid steps and returns the end state. If
  // samples is given, appends the state after every step n with n % every == 0.
  ScalarState run(const gear_dynamics::LaneSpec& lane, std::uint64_t seed, double delta0, double v0,
                  std::int64_t steps, std::int64_t every = 0,
                  std::vector<ScalarState>* samples = nullptr) const;

 private:
  void step(std::int64_t n, double mu, double load0, double load1, double& d, double& v) const;
  void rk4(double H, double la, double lb, double K, double qa, double qm, double qb, double& d,
           double& v) const;
  double acceleration(double d, double v, double load, double K, double Q) const;
  double friction(double local_phase) const { return c0_ + c1_ * (x_b_ + rb1_ * local_phase); }
  double stiffness(double local_phase) const { return local_phase < single_ ? k1_ : k2_; }

  double h_, b_, alpha_, q3_, c0_, c1_, x_b_, rb1_, k1_, k2_, phase0_, speed_, period_, single_;
};

}  // namespace gear_bench
