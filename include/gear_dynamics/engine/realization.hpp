// One realization of the gear SDE stepped with one lane's arithmetic (scalar doubles): the live
// node's one-lane path. It runs the kernel Ensemble runs (engine/rk4_kernel.hpp, the same operations
// in the same order), the same mesh plan and the same random stream NormalStream(seed, realization),
// so its path is bit for bit the path of the same LaneSpec in any Ensemble block, at any lane
// position (test_core: Realization.*). An Ensemble of one lane would pay for a full SIMD packet.
#pragma once

#include <cmath>
#include <cstdint>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"
#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics {

class Realization {
 public:
  static constexpr int kNormalChunk = Ensemble::kNormalChunk;  // normals drawn per refill

  Realization(const GearPair& gear, double time_step, const InitialState& initial, const LaneSpec& lane,
              std::uint64_t seed);

  // Advances by one grid step. Throws DivergenceError (lane 0) on a non-finite state.
  void step();
  // Back to t = 0 and the start of the random stream: the run repeats bit for bit.
  void reset();

  std::int64_t step_index() const { return n_; }
  double time() const { return static_cast<double>(n_) * h_; }
  double time_step() const { return h_; }
  std::uint64_t seed() const { return seed_; }
  const GearPair& gear() const { return gear_; }
  const MeshSchedule& mesh() const { return mesh_; }
  const LaneSpec& lane() const { return spec_; }

  double delta() const { return delta_; }
  double velocity() const { return velocity_; }
  double load() const { return load_; }

  // Run-time changes, as Ensemble's; they take effect at the next step.
  void set_mu(double mu) { spec_.mu = mu; }
  void set_sigma(double sigma);
  void set_drift(double drift) { spec_.drift = drift; }
  void set_load(double load) { load_ = load; }
  void set_state(double delta, double velocity) {
    delta_ = delta;
    velocity_ = velocity;
  }

 private:
  void refill_normals(std::uint64_t first_index);
  [[noreturn]] void report_divergence() const;

  GearPair gear_;
  MeshSchedule mesh_;
  double h_, sqrt_h_;
  InitialState initial_;
  LaneSpec spec_;
  NormalStream stream_;
  std::uint64_t seed_;
  std::int64_t n_ = 0;
  double delta_ = 0.0, velocity_ = 0.0, load_ = 0.0;
  // normals_[j] is normal normals_first_ + j of the stream (zeros without a stream).
  double normals_[kNormalChunk] = {};
  std::uint64_t normals_first_ = 0;
};

}  // namespace gear_dynamics
