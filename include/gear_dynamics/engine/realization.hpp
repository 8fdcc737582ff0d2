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

// What every one-realization path shares, whatever the model: the mesh plan, the time grid, the
// lane's settings and its random stream, and the load Phi that the stream drives. Realization
// (torsional) and BearingsRealization (engine/bearings.hpp) derive from it and add their state and
// their step; the load path is the same in both, bit for bit (Ensemble's too).
class RealizationBase {
 public:
  static constexpr int kNormalChunk = Ensemble::kNormalChunk;  // normals drawn per refill

  std::int64_t step_index() const { return n_; }
  double time() const { return static_cast<double>(n_) * h_; }
  double time_step() const { return h_; }
  std::uint64_t seed() const { return seed_; }
  const GearPair& gear() const { return gear_; }
  const MeshSchedule& mesh() const { return mesh_; }
  const LaneSpec& lane() const { return spec_; }
  double load() const { return load_; }

  // Run-time changes, as Ensemble's; they take effect at the next step.
  void set_mu(double mu) { spec_.mu = mu; }
  void set_sigma(double sigma);
  void set_drift(double drift) { spec_.drift = drift; }
  void set_load(double load) { load_ = load; }

 protected:
  RealizationBase(const GearPair& gear, double time_step, const InitialState& initial, const LaneSpec& lane,
                  std::uint64_t seed);
  // Back to t = 0 and the start of the random stream; Phi(0) from normal 0.
  void restart();
  // The normal that drives the next step (normal n + 1 of the stream).
  double next_normal();
  // Phi at the end of the next step from that normal: the load SDE's step (kernel::load_next).
  double next_load(double z) const;

  GearPair gear_;
  MeshSchedule mesh_;
  double h_, sqrt_h_;
  InitialState initial_;
  LaneSpec spec_;
  std::uint64_t seed_;
  std::int64_t n_ = 0;
  double load_ = 0.0;

 private:
  void refill_normals(std::uint64_t first_index);
  NormalStream stream_;
  // normals_[j] is normal normals_first_ + j of the stream (zeros without a stream).
  double normals_[kNormalChunk] = {};
  std::uint64_t normals_first_ = 0;
};

class Realization : public RealizationBase {
 public:
  Realization(const GearPair& gear, double time_step, const InitialState& initial, const LaneSpec& lane,
              std::uint64_t seed);

  // Advances by one grid step. Throws DivergenceError (lane 0) on a non-finite state.
  void step();
  // Back to t = 0 and the start of the random stream: the run repeats bit for bit.
  void reset();

  double delta() const { return delta_; }
  double velocity() const { return velocity_; }

  void set_state(double delta, double velocity) {
    delta_ = delta;
    velocity_ = velocity;
  }

 private:
  [[noreturn]] void report_divergence() const;

  double delta_ = 0.0, velocity_ = 0.0;
};

}  // namespace gear_dynamics
