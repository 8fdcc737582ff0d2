#include "gear_dynamics/observers.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace gear_dynamics {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

WindowRange::WindowRange(int lanes, std::int64_t window_steps, std::int64_t block_steps)
    : window_(window_steps), block_(block_steps) {
  if (lanes <= 0 || window_steps < 0 || block_steps <= 0)
    throw std::invalid_argument("WindowRange: needs lanes > 0, window_steps >= 0, block_steps > 0");
  // Blocks that can overlap a window: the current one and those reaching back window_ points.
  const auto slots = static_cast<Eigen::Index>(window_ / block_ + 2);
  dmax_.resize(lanes, slots);
  dmin_.resize(lanes, slots);
  vmax_.resize(lanes, slots);
  vmin_.resize(lanes, slots);
  slot_block_.assign(slots, -1);
  reset();
}

void WindowRange::reset() {
  last_ = -1;
  std::fill(slot_block_.begin(), slot_block_.end(), -1);
}

void WindowRange::observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
                          const Eigen::Ref<const Eigen::ArrayXd>& velocity) {
  const std::int64_t block = n / block_;
  const auto k = static_cast<Eigen::Index>(block % static_cast<std::int64_t>(slot_block_.size()));
  if (slot_block_[k] != block) {  // first sample of a new block: it takes the oldest slot
    slot_block_[k] = block;
    dmax_.col(k) = delta;
    dmin_.col(k) = delta;
    vmax_.col(k) = velocity;
    vmin_.col(k) = velocity;
  } else {
    dmax_.col(k) = dmax_.col(k).max(delta);
    dmin_.col(k) = dmin_.col(k).min(delta);
    vmax_.col(k) = vmax_.col(k).max(velocity);
    vmin_.col(k) = vmin_.col(k).min(velocity);
  }
  last_ = n;
}

void WindowRange::reduce(Eigen::ArrayXd& dmax, Eigen::ArrayXd& dmin, Eigen::ArrayXd& vmax,
                         Eigen::ArrayXd& vmin) const {
  const auto lanes = dmax_.rows();
  dmax.setConstant(lanes, -kInf);
  dmin.setConstant(lanes, kInf);
  vmax.setConstant(lanes, -kInf);
  vmin.setConstant(lanes, kInf);
  if (last_ < 0) return;
  const std::int64_t first = last_ - window_;  // first grid point of the window
  for (std::size_t k = 0; k < slot_block_.size(); ++k) {
    const std::int64_t b = slot_block_[k];
    // A block counts if it overlaps [first, last_] (its last point is (b + 1) * block_ - 1).
    if (b < 0 || (b + 1) * block_ - 1 < first || b * block_ > last_) continue;
    const auto kk = static_cast<Eigen::Index>(k);
    dmax = dmax.max(dmax_.col(kk));
    dmin = dmin.min(dmin_.col(kk));
    vmax = vmax.max(vmax_.col(kk));
    vmin = vmin.min(vmin_.col(kk));
  }
}

Eigen::ArrayXd WindowRange::delta_range() const {
  Eigen::ArrayXd dmax, dmin, vmax, vmin;
  reduce(dmax, dmin, vmax, vmin);
  return last_ < 0 ? Eigen::ArrayXd::Zero(dmax.size()).eval() : (dmax - dmin).eval();
}

Eigen::ArrayXd WindowRange::velocity_range() const {
  Eigen::ArrayXd dmax, dmin, vmax, vmin;
  reduce(dmax, dmin, vmax, vmin);
  return last_ < 0 ? Eigen::ArrayXd::Zero(vmax.size()).eval() : (vmax - vmin).eval();
}

Eigen::ArrayXd WindowRange::center_distance() const {
  return (delta_range() * velocity_range()).sqrt();
}

SteadyStateTime::SteadyStateTime(int lanes, double backlash, double tolerance)
    : backlash_(backlash), tolerance_(tolerance), last_(Eigen::ArrayXd::Zero(lanes)) {}

void SteadyStateTime::observe(double t, const Eigen::Ref<const Eigen::ArrayXd>& delta) {
  last_ = ((delta - backlash_).abs() > tolerance_).select(t, last_);
}

Snapshots::Snapshots(int lanes, std::vector<std::int64_t> steps) : steps_(std::move(steps)) {
  if (!std::is_sorted(steps_.begin(), steps_.end()))
    throw std::invalid_argument("Snapshots: steps must be in increasing order");
  delta_.setZero(lanes, static_cast<Eigen::Index>(steps_.size()));
  velocity_.setZero(lanes, static_cast<Eigen::Index>(steps_.size()));
  load_.setZero(lanes, static_cast<Eigen::Index>(steps_.size()));
}

void Snapshots::observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
                        const Eigen::Ref<const Eigen::ArrayXd>& velocity,
                        const Eigen::Ref<const Eigen::ArrayXd>& load) {
  while (next_ < steps_.size() && steps_[next_] == n) {  // a step may be asked for twice
    const auto k = static_cast<Eigen::Index>(next_++);
    delta_.col(k) = delta;
    velocity_.col(k) = velocity;
    load_.col(k) = load;
  }
}

}  // namespace gear_dynamics
