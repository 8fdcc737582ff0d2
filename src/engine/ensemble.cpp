#include "gear_dynamics/engine/ensemble.hpp"

#include "dispatch.hpp"

#include <cmath>
#include <sstream>

#include "gear_dynamics/engine/bearings.hpp"

namespace gear_dynamics {

namespace {

int padded(std::size_t lanes) {
  return static_cast<int>((lanes + Ensemble::kPacket - 1) / Ensemble::kPacket) * Ensemble::kPacket;
}

}  // namespace

Ensemble::Ensemble(const GearPair& gear, double time_step, const InitialState& initial,
                   std::vector<LaneSpec> lanes, std::uint64_t seed)
    : gear_(gear), mesh_(gear, time_step), h_(time_step), initial_(initial), spec_(std::move(lanes)),
      seed_(seed) {
  if (spec_.empty()) throw std::invalid_argument("Ensemble: a block needs at least one lane");
  for (const LaneSpec& s : spec_) {
    if (!s.stochastic && (s.sigma != 0.0 || s.load_sd != 0.0))
      throw std::invalid_argument("Ensemble: a lane without a random stream needs sigma = 0 and load_sd = 0");
  }
  const int p = padded(spec_.size());
  for (int first = 0; first < p; first += kPacket) {
    std::uint64_t realizations[kPacket] = {};
    bool any = false;
    for (int i = first; i < first + kPacket; ++i) {
      const bool stochastic = i < static_cast<int>(spec_.size()) && spec_[i].stochastic;
      if (stochastic) realizations[i - first] = spec_[i].realization;
      any = any || stochastic;
    }
    if (!any) continue;  // its normals stay zero
    streams_.emplace_back(seed, realizations);
    stream_packet_.push_back(first / kPacket);
    for (int i = first; i < first + kPacket; ++i)
      if (!(i < static_cast<int>(spec_.size()) && spec_[i].stochastic)) silent_.push_back(i);
  }
  delta_.setZero(p);
  velocity_.setZero(p);
  load_.setZero(p);
  mu_.setZero(p);
  sigma_.setZero(p);
  drift_.setZero(p);
  normals_.setZero(p, kNormalChunk);
  if (gear.in.model == GearModel::kBearings) {
    bearings_ = std::make_shared<const BearingsModel>(gear_);
    model_state_.setZero(BearingsModel::kStates, p);
  }
  reset();
}

void Ensemble::reset() {
  n_ = 0;
  refill_normals(0);
  for (int i = 0; i < lanes(); ++i) {
    const LaneSpec& s = spec_[i];
    delta_[i] = initial_.deflection;
    velocity_[i] = initial_.velocity;
    // Normal 0 of a stream gives Phi(0); normal n + 1 drives step n.
    load_[i] = s.load_mean + s.load_sd * normals_(i, 0);
    mu_[i] = s.mu;
    sigma_[i] = s.sigma;
    drift_[i] = s.drift;
  }
  if (bearings_) {  // at rest on the bearings: delta_m = delta_t
    model_state_.setZero();
    model_state_.row(BearingsModel::kDelta).head(lanes()).setConstant(initial_.deflection);
    model_state_.row(BearingsModel::kDeltaDot).head(lanes()).setConstant(initial_.velocity);
  }
}

void Ensemble::set_mu(int lane, double mu) { spec_.at(lane).mu = mu_[lane] = mu; }

void Ensemble::set_sigma(int lane, double sigma) {
  if (!spec_.at(lane).stochastic && sigma != 0.0)
    throw std::invalid_argument("Ensemble: lane without a random stream cannot take sigma != 0");
  spec_[lane].sigma = sigma_[lane] = sigma;
}

void Ensemble::set_drift(int lane, double drift) { spec_.at(lane).drift = drift_[lane] = drift; }

void Ensemble::set_load(int lane, double load) {
  (void)spec_.at(lane);  // bounds check
  load_[lane] = load;
}

void Ensemble::set_model_state(int lane, const double* state) {
  if (lane < 0 || lane >= lanes()) throw std::out_of_range("Ensemble::set_model_state: no such lane");
  if (!bearings_)
    throw std::invalid_argument("Ensemble::set_model_state: the torsional model's state is (delta, delta_dot); "
                                "use set_state");
  const BearingsModel::State y = Eigen::Map<const BearingsModel::State>(state);
  model_state_.col(lane) = y;
  delta_[lane] = bearings_->deflection(y);
  velocity_[lane] = bearings_->deflection_rate(y);
}

void Ensemble::set_state(int lane, double delta, double velocity) {
  if (lane < 0 || lane >= lanes()) throw std::out_of_range("Ensemble::set_state: no such lane");
  if (bearings_)
    throw std::invalid_argument("Ensemble::set_state: gear_pair.model = bearings has no (delta, delta_dot) state; "
                                "allowed: torsional");
  delta_[lane] = delta;
  velocity_[lane] = velocity;
}

void Ensemble::refill_normals(std::uint64_t first_index) {
  normals_first_ = first_index;  // a multiple of kNormalChunk: one whole generator block
  static_assert(kNormalChunk == 2 * NormalLanes::kBlockPairs);
  for (std::size_t k = 0; k < streams_.size(); ++k)
    streams_[k].block(first_index / 2, &normals_(stream_packet_[k] * kPacket, 0), normals_.rows());
  for (int i : silent_) normals_.row(i).setZero();
}

void Ensemble::step() {
  const auto index = static_cast<std::uint64_t>(n_) + 1;  // normal of this step
  if (index >= normals_first_ + kNormalChunk) refill_normals(normals_first_ + kNormalChunk);
  if (bearings_) {
    step_bearings(static_cast<Eigen::Index>(index - normals_first_));
    return;
  }
  // The lanes' arithmetic runs in the instruction-set variant chosen for the process
  // (src/engine/dispatched/ensemble_step.cpp).
  const dispatch::EnsembleStep lanes{&mesh_,
                                     n_,
                                     h_,
                                     std::sqrt(h_),
                                     gear_.in.backlash,
                                     gear_.damping_coefficient,
                                     gear_.q3,
                                     delta_.data(),
                                     velocity_.data(),
                                     load_.data(),
                                     mu_.data(),
                                     sigma_.data(),
                                     drift_.data(),
                                     &normals_(0, static_cast<Eigen::Index>(index - normals_first_)),
                                     delta_.size()};
  const bool finite = dispatch::kernels().ensemble_step(lanes);
  ++n_;
  if (!finite) report_divergence();
}

void Ensemble::step_bearings(Eigen::Index column) {
  // The lanes in SIMD packets, each lane BearingsRealization's arithmetic (the same load step and
  // bearings_step's bits), so that a realization's bits depend neither on its block nor on its lane.
  const dispatch::BearingsEnsembleStep step{bearings_.get(),
                                             &gear_,
                                             &mesh_,
                                             n_,
                                             h_,
                                             std::sqrt(h_),
                                             model_state_.data(),
                                             model_state_.cols(),
                                             delta_.data(),
                                             velocity_.data(),
                                             load_.data(),
                                             mu_.data(),
                                             sigma_.data(),
                                             drift_.data(),
                                             &normals_(0, column),
                                             delta_.size()};
  const bool finite = dispatch::kernels().bearings_ensemble_step(step);
  ++n_;
  if (finite) return;
  for (int i = 0; i < lanes(); ++i) {
    if (!model_state_.col(i).allFinite())
      throw bearings_divergence(spec_[i].realization, i, delta_[i], time());
  }
}

void Ensemble::report_divergence() const {
  for (int i = 0; i < lanes(); ++i) {
    if (std::isfinite(delta_[i]) && std::isfinite(velocity_[i])) continue;
    std::ostringstream msg;
    msg << "gear model diverged: realization " << spec_[i].realization << " (lane " << i
        << ", mu " << spec_[i].mu << ") has delta = " << delta_[i] << " m, delta_dot = "
        << velocity_[i] << " m/s at t = " << time() << " s";
    throw DivergenceError(msg.str(), i, spec_[i].realization, time());
  }
}

}  // namespace gear_dynamics
