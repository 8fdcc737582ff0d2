#include "gear_dynamics/engine/observers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace gear_dynamics {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

WindowRange::WindowRange(int lanes, std::int64_t window_steps, std::int64_t block_steps)
    : lanes_(lanes), window_(window_steps), block_(block_steps) {
  if (lanes <= 0 || window_steps < 0 || block_steps <= 0 || window_steps % block_steps != 0)
    throw std::invalid_argument("WindowRange: needs lanes > 0, window_steps >= 0, block_steps > 0 dividing window_steps");
  segment_ = window_ / block_ + 1;  // an exact window spans this many blocks
  const auto segment = static_cast<Eigen::Index>(segment_);
  blocks_.resize(4 * lanes, segment);
  suffix_.resize(4 * lanes, segment);
  prefix_.resize(4 * lanes);
  reset();
}

void WindowRange::reset() {
  last_ = block_index_ = segment_index_ = -1;
  block_end_ = 0;
  blocks_.setConstant(-kInf);
  suffix_.setConstant(-kInf);
  prefix_.setConstant(-kInf);
}

Eigen::ArrayXXd::ColXpr WindowRange::block_of(std::int64_t n) {
  const std::int64_t block = n / block_;
  if (block != block_index_) {
    const std::int64_t segment = block / segment_;
    if (segment != segment_index_) {
      if (segment == segment_index_ + 1) {  // the finished segment's suffix maxima
        suffix_.col(segment_ - 1) = blocks_.col(segment_ - 1);
        for (Eigen::Index i = segment_ - 2; i >= 0; --i) suffix_.col(i) = blocks_.col(i).max(suffix_.col(i + 1));
      } else {  // first sample, or a gap: the previous segment holds nothing observed
        suffix_.setConstant(-kInf);
      }
      blocks_.setConstant(-kInf);
      prefix_.setConstant(-kInf);
      segment_index_ = segment;
    } else {
      prefix_ = prefix_.max(blocks_.col(block_index_ - segment * segment_));
    }
    block_index_ = block;
    block_end_ = (block + 1) * block_;
  }
  last_ = n;
  const Eigen::Index column = static_cast<Eigen::Index>(block - segment_index_ * segment_);
  current_ = column * blocks_.rows();
  return blocks_.col(column);
}

void WindowRange::observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
                          const Eigen::Ref<const Eigen::ArrayXd>& velocity) {
  auto current = block_of(n);
  const auto l = static_cast<Eigen::Index>(lanes_);
  current.segment(0, l) = current.segment(0, l).max(delta);
  current.segment(l, l) = current.segment(l, l).max(-delta);
  current.segment(2 * l, l) = current.segment(2 * l, l).max(velocity);
  current.segment(3 * l, l) = current.segment(3 * l, l).max(-velocity);
}

void WindowRange::observe_extrema(std::int64_t n, double max_delta, double max_minus_delta, double max_velocity,
                                  double max_minus_velocity) {
  if (lanes_ != 1) throw std::logic_error("WindowRange::observe_extrema: one lane only");
  auto current = block_of(n);
  // std::max(current, x): Eigen's max above, with the same operand order.
  current[0] = std::max(current[0], max_delta);
  current[1] = std::max(current[1], max_minus_delta);
  current[2] = std::max(current[2], max_velocity);
  current[3] = std::max(current[3], max_minus_velocity);
}

Eigen::ArrayXd WindowRange::reduce() const {
  if (last_ < 0) return Eigen::ArrayXd::Constant(4 * lanes_, -kInf);
  // The window's blocks: first .. block_index_, block_index_ - first + 1 = segment_ of them.
  const std::int64_t first = block_index_ - (segment_ - 1);
  Eigen::ArrayXd m = prefix_.max(blocks_.col(block_index_ - segment_index_ * segment_));
  if (first < segment_index_ * segment_) m = m.max(suffix_.col(first - (segment_index_ - 1) * segment_));
  return m;
}

Eigen::ArrayXd WindowRange::delta_range() const {
  if (last_ < 0) return Eigen::ArrayXd::Zero(lanes_);
  const Eigen::ArrayXd m = reduce();
  return m.segment(0, lanes_) + m.segment(lanes_, lanes_);  // max + (-min)
}

Eigen::ArrayXd WindowRange::velocity_range() const {
  if (last_ < 0) return Eigen::ArrayXd::Zero(lanes_);
  const Eigen::ArrayXd m = reduce();
  return m.segment(2 * lanes_, lanes_) + m.segment(3 * lanes_, lanes_);
}

Eigen::ArrayXd WindowRange::center_distance() const {
  return (delta_range() * velocity_range()).sqrt();
}

double WindowRange::center_distance(int lane) const {
  if (last_ < 0) return std::sqrt(0.0 * 0.0);
  // reduce() and the ranges for one lane: the same maxima, sums and product in the same order.
  const Eigen::Index col = static_cast<Eigen::Index>(block_index_ - segment_index_ * segment_);
  const std::int64_t first = block_index_ - (segment_ - 1);
  const bool suffix = first < segment_index_ * segment_;
  const Eigen::Index scol = suffix ? static_cast<Eigen::Index>(first - (segment_index_ - 1) * segment_) : 0;
  double m[4];
  for (int k = 0; k < 4; ++k) {
    const Eigen::Index row = k * lanes_ + lane;
    m[k] = std::max(prefix_[row], blocks_(row, col));
    if (suffix) m[k] = std::max(m[k], suffix_(row, scol));
  }
  return std::sqrt((m[0] + m[1]) * (m[2] + m[3]));
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

bool on_step_grid(double t, double h) {
  const double r = t / h;
  return std::abs(r - std::round(r)) <= 1e-9;
}

double hermite_in_step(double x0, double v0, double x1, double v1, double s, double h) {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * x0 + (s3 - 2 * s2 + s) * h * v0 + (-2 * s3 + 3 * s2) * x1 + (s3 - s2) * h * v1;
}

double hermite_slope_in_step(double x0, double v0, double x1, double v1, double s, double h) {
  const double s2 = s * s;
  return ((6 * s2 - 6 * s) * (x0 - x1)) / h + (3 * s2 - 4 * s + 1) * v0 + (3 * s2 - 2 * s) * v1;
}

double linear_in_step(double x0, double x1, double s) { return x0 + s * (x1 - x0); }

PoincareSampler::PoincareSampler(int lanes, double time_step, double period, double offset, double end)
    : h_(time_step),
      period_(period),
      offset_(offset),
      end_(end),
      exact_(on_step_grid(offset, time_step) && on_step_grid(period, time_step)),
      m_(std::llround(period / time_step)),
      n0_(std::llround(offset / time_step)),
      delta_prev_(lanes),
      velocity_prev_(lanes),
      points_(static_cast<std::size_t>(lanes)) {
  if (!(period > 0) || !(offset >= 0)) throw std::invalid_argument("PoincareSampler: period must be > 0 and offset >= 0");
}

void PoincareSampler::emit(double t, const Eigen::Ref<const Eigen::ArrayXd>& delta,
                           const Eigen::Ref<const Eigen::ArrayXd>& velocity, bool grid, double s) {
  for (Eigen::Index l = 0; l < delta.size(); ++l) {
    SectionPoint p{t, delta[l], velocity[l]};
    if (!grid) {
      p.delta = hermite_in_step(delta_prev_[l], velocity_prev_[l], delta[l], velocity[l], s, h_);
      p.delta_dot = hermite_slope_in_step(delta_prev_[l], velocity_prev_[l], delta[l], velocity[l], s, h_);
    }
    points_[static_cast<std::size_t>(l)].push_back(p);
  }
  ++k_;
}

void PoincareSampler::observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
                              const Eigen::Ref<const Eigen::ArrayXd>& velocity) {
  const double t = static_cast<double>(n) * h_;
  if (exact_) {
    if (n == n0_ + k_ * m_ && t <= end_ + 1e-9 * h_) emit(t, delta, velocity, true, 1.0);
    return;
  }
  if (due_) {  // t_k was in the step just taken: poincare_section's s = (t_k - t_n) / h
    const double tk = offset_ + static_cast<double>(k_) * period_;
    emit(tk, delta, velocity, false, (tk - t_prev_) / h_);
    due_ = false;
  }
  const double next = offset_ + static_cast<double>(k_) * period_;
  if (next <= t + h_ && next <= end_) {
    due_ = true;
    t_prev_ = t;
    delta_prev_ = delta;
    velocity_prev_ = velocity;
  }
}

}  // namespace gear_dynamics
