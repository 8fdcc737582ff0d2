#include "gear_dynamics/engine/realization.hpp"

#include <sstream>
#include <stdexcept>

#include "dispatch.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"

namespace gear_dynamics {

RealizationBase::RealizationBase(const GearPair& gear, double time_step, const InitialState& initial,
                                 const LaneSpec& lane, std::uint64_t seed)
    : gear_(gear), mesh_(gear, time_step), h_(time_step), sqrt_h_(std::sqrt(time_step)), initial_(initial),
      spec_(lane), seed_(seed), stream_(seed, lane.realization) {
  if (!spec_.stochastic && (spec_.sigma != 0.0 || spec_.load_sd != 0.0))
    throw std::invalid_argument("Realization: a lane without a random stream needs sigma = 0 and load_sd = 0");
}

void RealizationBase::restart() {
  n_ = 0;
  refill_normals(0);
  // Normal 0 of the stream gives Phi(0); normal n + 1 drives step n (as Ensemble::reset).
  load_ = spec_.load_mean + spec_.load_sd * normals_[0];
}

double RealizationBase::next_normal() {
  const auto index = static_cast<std::uint64_t>(n_) + 1;  // normal of this step
  if (index >= normals_first_ + kNormalChunk) refill_normals(normals_first_ + kNormalChunk);
  return normals_[index - normals_first_];
}

double RealizationBase::next_load(double z) const {
  return kernel::load_next<double>(load_, spec_.drift, spec_.sigma, z, h_, sqrt_h_);
}

void RealizationBase::set_sigma(double sigma) {
  if (!spec_.stochastic && sigma != 0.0)
    throw std::invalid_argument("Realization: a lane without a random stream cannot take sigma != 0");
  spec_.sigma = sigma;
}

void RealizationBase::refill_normals(std::uint64_t first_index) {
  normals_first_ = first_index;
  if (spec_.stochastic) stream_.fill(first_index, normals_, kNormalChunk);  // else they stay zero
}

Realization::Realization(const GearPair& gear, double time_step, const InitialState& initial,
                         const LaneSpec& lane, std::uint64_t seed)
    : RealizationBase(gear, time_step, initial, lane, seed) {
  if (gear.in.model != GearModel::kTorsional)  // BearingsRealization steps it (engine/bearings.hpp)
    throw std::invalid_argument(
        "gear_pair.model = bearings: Realization steps the torsional model; BearingsRealization steps bearings");
  reset();
}

void Realization::step() {
  const double z = next_normal();
  double d = delta_, v = velocity_;
  // The lane's arithmetic in the process's instruction-set variant (src/engine/dispatched/).
  dispatch::kernels().realization_step({&mesh_, n_, h_, sqrt_h_, gear_.in.backlash, gear_.damping_coefficient,
                                        gear_.q3, spec_.mu, spec_.drift, spec_.sigma, z, &d, &v, &load_});
  delta_ = d;
  velocity_ = v;
  ++n_;
  // Ensemble's test: the sum first (one test per step), the states only when it is not finite.
  if (!std::isfinite(d + v) && !(std::isfinite(d) && std::isfinite(v))) report_divergence();
}

void Realization::reset() {
  restart();
  delta_ = initial_.deflection;
  velocity_ = initial_.velocity;
}

void Realization::report_divergence() const {
  std::ostringstream msg;
  msg << "gear model diverged: realization " << spec_.realization << " (lane 0, mu " << spec_.mu
      << ") has delta = " << delta_ << " m, delta_dot = " << velocity_ << " m/s at t = " << time() << " s";
  throw DivergenceError(msg.str(), 0, spec_.realization, time());
}

}  // namespace gear_dynamics
