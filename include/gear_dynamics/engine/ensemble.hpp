// The gear SDE (doc/model.md §2) for a block of realizations stepped together: structure of arrays,
// one SIMD lane per realization, RK4 with the stiffness switches split out (doc/model.md §5).
// gear_pair.model = bearings runs here too, in SIMD packets of lanes of its own kernel
// (src/engine/dispatched/bearings_step.cpp, bit for bit bearings_step, engine/bearings.hpp), its
// delta and delta_dot the mesh deflection delta_m and its rate: the observers, the recorder and the
// batch see it as they see the torsional model.
// The CLI and the Monte Carlo batch run this class; the live node steps its one realization with
// Realization (engine/realization.hpp), the same kernel (engine/rk4_kernel.hpp) on one lane. Every
// lane's arithmetic is independent of the other lanes (the build uses -ffp-contract=off), so a
// realization's numbers do not depend on the block it runs in, nor on the lane width.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"

namespace gear_dynamics {

class BearingsModel;  // engine/bearings.hpp

// Generation of the engine's numbers: raised whenever a change alters any run's results (1: Box-Muller
// normals, unfused RK4; 2: Boost's ziggurat normals, fused multiply-adds; 3: backlash crossings
// located, h = 2.5 us by default). A batch folder records it, so a resume never mixes bags of two
// generations (doc/batch-folder.md).
constexpr int kNumbersGeneration = 3;

// What differs between the realizations of a block.
struct LaneSpec {
  double mu = 0.0;               // friction coefficient [-]
  double sigma = 0.0;            // load noise intensity [m/s^2/sqrt(s)]
  double drift = 0.0;            // lambda [m/s^3]
  double load_mean = 20.0;       // E[Phi(0)] [m/s^2]
  double load_sd = 0.0;          // sd of Phi(0) [m/s^2]; Phi(0) = load_mean + load_sd * Z_0
  std::uint64_t realization = 0; // index of the random stream
  bool stochastic = true;        // false: no random stream at all (sigma and load_sd must be 0)
};

struct InitialState {
  double deflection = 0.0;  // delta(0) [m]
  double velocity = 0.0;    // delta_dot(0) [m/s]
};

// Thrown when a lane's state stops being finite.
class DivergenceError : public std::runtime_error {
 public:
  DivergenceError(const std::string& what, int lane, std::uint64_t realization, double time)
      : std::runtime_error(what), lane(lane), realization(realization), time(time) {}
  int lane;
  std::uint64_t realization;
  double time;
};

class Ensemble {
 public:
  static constexpr int kPacket = 8;          // lanes per SIMD packet; blocks are padded to it
  // Steps of normals drawn per refill: one generator block, and lanes x chunk stays in L1.
  static constexpr int kNormalChunk = 2 * NormalStream::kBlockPairs;

  Ensemble(const GearPair& gear, double time_step, const InitialState& initial,
           std::vector<LaneSpec> lanes, std::uint64_t seed);

  // Advances every lane by one grid step. Throws DivergenceError on a non-finite state.
  void step();
  // Back to t = 0 and the start of every random stream: the run repeats bit for bit.
  void reset();

  int lanes() const { return static_cast<int>(spec_.size()); }
  std::int64_t step_index() const { return n_; }
  double time() const { return static_cast<double>(n_) * h_; }
  double time_step() const { return h_; }
  std::uint64_t seed() const { return seed_; }
  const GearPair& gear() const { return gear_; }
  // The bearings model of gear(), built once; null for the torsional model.
  const BearingsModel* bearings_model() const { return bearings_.get(); }
  const MeshSchedule& mesh() const { return mesh_; }
  const LaneSpec& lane(int i) const { return spec_[i]; }

  // State of the real lanes (padding excluded); for the bearings model delta_m and its rate.
  auto delta() const { return delta_.head(lanes()); }
  auto velocity() const { return velocity_.head(lanes()); }
  auto load() const { return load_.head(lanes()); }
  // The same with the padding to whole packets (padding lanes stay at rest, 0): for passes in packets.
  int padded_lanes() const { return static_cast<int>(delta_.size()); }
  const Eigen::ArrayXd& padded_delta() const { return delta_; }
  const Eigen::ArrayXd& padded_velocity() const { return velocity_; }
  // The whole state of each lane of a model with more than (delta, delta_dot), one column per lane
  // (BearingsModel::State; bearings_outputs(ensemble, mesh_point, lane) reads it); empty for the torsional model.
  auto model_state() const { return model_state_.leftCols(bearings_ ? lanes() : 0); }

  // Run-time changes; they take effect at the next step boundary.
  void set_mu(int lane, double mu);
  void set_sigma(int lane, double sigma);
  void set_drift(int lane, double drift);
  // Sets the lane's load state Phi [m/s^2] now; the load SDE goes on from it (an external load).
  void set_load(int lane, double load);
  // Overwrites one lane's (delta, delta_dot) at the current step; the load and the random stream
  // are left alone (the two-trajectory Lyapunov method, doc/nonlinear-dynamics.md §4). Torsional
  // model only (the bearings model's state is not (delta, delta_dot)).
  void set_state(int lane, double delta, double velocity);
  // gear_pair.model = bearings: lane's whole state, BearingsModel::kStates values in its Index order
  // (delta and delta_dot follow as delta_m and its rate). Throws for the torsional model.
  void set_model_state(int lane, const double* state);

 private:
  void refill_normals(std::uint64_t first_index);
  void report_divergence() const;
  // The bearings model's step of every lane, with normal column `column` (src/engine/ensemble.cpp).
  void step_bearings(Eigen::Index column);

  GearPair gear_;
  MeshSchedule mesh_;
  std::shared_ptr<const BearingsModel> bearings_;  // bearings_model()
  double h_;
  InitialState initial_;
  std::vector<LaneSpec> spec_;
  // One generator per packet of kPacket lanes (NormalLanes: each lane its own stream); packets
  // without a stochastic lane have none. Lanes without a stream get zeros (silent_).
  std::vector<NormalLanes> streams_;
  std::vector<int> stream_packet_;  // packet of streams_[k]
  std::vector<int> silent_;         // lanes of those packets without a stream (padding included)
  std::uint64_t seed_;
  std::int64_t n_ = 0;

  // Padded to a multiple of kPacket.
  Eigen::ArrayXd delta_, velocity_, load_, mu_, sigma_, drift_;
  // model_state(), padded; row-major: each component's lanes side by side, as the SIMD kernel reads them.
  Eigen::Array<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> model_state_;
  // Padded lanes x kNormalChunk: column j holds normal normals_first_ + j of each lane's stream.
  static_assert(Ensemble::kPacket == NormalLanes::kLanes);
  // Chunks start at multiples of kNormalChunk, whole blocks of the stream's generator.
  Eigen::ArrayXXd normals_;
  std::uint64_t normals_first_ = 0;
};

}  // namespace gear_dynamics
