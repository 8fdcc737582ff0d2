// Online observers of a block of realizations (doc/model.md §8). They see every integration grid
// point and keep a fixed amount of memory, never the path.
#pragma once

#include <Eigen/Core>
#include <immintrin.h>
#include <cmath>
#include <cstdint>
#include <vector>

namespace gear_dynamics {

// Ranges of delta and delta_dot over the trailing window [t - W, t] (clipped at 0), hence the
// instantaneous center distance d(t) = sqrt(range(delta) * range(delta_dot)) (paper Eq. 22).
// Keeps extrema per block of `block_steps` grid points (block_steps must divide window_steps) and
// combines them by van Herk / Gil-Werman: the window's blocks are a suffix of the previous segment
// of window/block + 1 blocks and a prefix of the current one. Memory is 2 (window/block + 1)
// blocks; observe and every query cost O(1) amortized, however often d(t) is read. The window is
// exact when the last observed step is a multiple of block_steps; otherwise it also covers up to
// block_steps - 1 earlier grid points.
class WindowRange {
 public:
  WindowRange(int lanes, std::int64_t window_steps, std::int64_t block_steps);

  // Sample of grid step n; steps must arrive in order, one after the other.
  void observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
               const Eigen::Ref<const Eigen::ArrayXd>& velocity);
  // One lane (lanes == 1): the extrema of grid steps that all lie in the block of step n, the last
  // of them n; the same as observing each of those steps in order (a max keeps the first of equal
  // values either way). The live node folds each step into four scalars and merges them here.
  void observe_extrema(std::int64_t n, double max_delta, double max_minus_delta, double max_velocity,
                       double max_minus_velocity);
  void reset();
  // Observing in packets of N lanes (simulate()'s one pass per step over a block padded to whole
  // packets): start(n) once for grid step n, then observe_packet(first, ...) for lanes first .. first + N - 1.
  // The same maxima as observe(n, delta, velocity).
  void start(std::int64_t n) {
    if (n < block_end_) {  // still in the current block: no division (this runs at every step)
      last_ = n;
      return;
    }
    block_of(n);
  }
  template <int N>
  void observe_packet(Eigen::Index first, const Eigen::Array<double, N, 1>& delta,
                      const Eigen::Array<double, N, 1>& velocity) {
    using Lanes = Eigen::Map<Eigen::Array<double, N, 1>>;
    const auto l = static_cast<Eigen::Index>(lanes_);
    double* current = blocks_.data() + current_;
    Lanes max_delta(current + first), max_minus_delta(current + l + first);
    Lanes max_velocity(current + 2 * l + first), max_minus_velocity(current + 3 * l + first);
    max_delta = max_delta.max(delta);
    max_minus_delta = max_minus_delta.max(-delta);
    max_velocity = max_velocity.max(velocity);
    max_minus_velocity = max_minus_velocity.max(-velocity);
  }

  Eigen::ArrayXd delta_range() const;
  Eigen::ArrayXd velocity_range() const;
  Eigen::ArrayXd center_distance() const;  // [m s^-1/2] in SI
  double center_distance(int lane) const;  // the same for one lane, without allocating

  std::int64_t block_steps() const { return block_; }
  int capacity_blocks() const { return static_cast<int>(segment_); }

 private:
  // Maxima of (delta, -delta, delta_dot, -delta_dot) stacked: one max covers all four extrema.
  Eigen::ArrayXd reduce() const;
  // Moves to step n's block (n in order) and returns its column (also current_).
  Eigen::ArrayXXd::ColXpr block_of(std::int64_t n);
  int lanes_;
  std::int64_t window_, block_, segment_;  // segment_ = blocks per segment = window/block + 1
  std::int64_t last_ = -1, block_index_ = -1, segment_index_ = -1;
  std::int64_t block_end_ = 0;  // first step after block block_index_ (0 before any)
  Eigen::ArrayXXd blocks_;  // column i: block segment_index_ * segment_ + i (-inf = no sample)
  Eigen::ArrayXXd suffix_;  // column i: blocks i..segment_-1 of the previous segment
  Eigen::ArrayXd prefix_;   // blocks of the current segment before block_index_
  Eigen::Index current_ = 0;  // offset of block block_index_'s column in blocks_ (an offset: copies stay right)
};

// t_ss: the last grid time at which |delta - b| > tolerance, 0 if none (doc/model.md §8).
class SteadyStateTime {
 public:
  SteadyStateTime(int lanes, double backlash, double tolerance);
  void observe(double t, const Eigen::Ref<const Eigen::ArrayXd>& delta);
  // The same for lanes first .. first + N - 1 (a packet of simulate()'s one pass per step).
  template <int N>
  void observe_packet(double t, Eigen::Index first, const Eigen::Array<double, N, 1>& delta) {
    double* last = last_.data() + first;
#ifdef __AVX512F__
    if constexpr (N == 8) {  // GCC makes the loop below scalar stores, which stall the next load
      const __m512d off = _mm512_abs_pd(_mm512_sub_pd(_mm512_loadu_pd(delta.data()), _mm512_set1_pd(backlash_)));
      const __mmask8 far = _mm512_cmp_pd_mask(off, _mm512_set1_pd(tolerance_), _CMP_GT_OQ);  // as >: false on NaN
      _mm512_storeu_pd(last, _mm512_mask_blend_pd(far, _mm512_loadu_pd(last), _mm512_set1_pd(t)));
      return;
    }
#elif defined(__AVX__)
    if constexpr (N % 4 == 0) {  // the same with 4 lanes per vector
      const __m256d sign = _mm256_set1_pd(-0.0);
      for (int i = 0; i < N; i += 4) {
        const __m256d off = _mm256_andnot_pd(sign, _mm256_sub_pd(_mm256_loadu_pd(delta.data() + i), _mm256_set1_pd(backlash_)));
        const __m256d far = _mm256_cmp_pd(off, _mm256_set1_pd(tolerance_), _CMP_GT_OQ);
        _mm256_storeu_pd(last + i, _mm256_blendv_pd(_mm256_loadu_pd(last + i), _mm256_set1_pd(t), far));
      }
      return;
    }
#endif
    for (int i = 0; i < N; ++i) last[i] = std::fabs(delta[i] - backlash_) > tolerance_ ? t : last[i];
  }
  void reset() { last_.setZero(); }
  const Eigen::ArrayXd& time() const { return last_; }

 private:
  double backlash_, tolerance_;
  Eigen::ArrayXd last_;
};

// (delta, delta_dot, Phi) of every lane at chosen grid steps.
class Snapshots {
 public:
  Snapshots(int lanes, std::vector<std::int64_t> steps);
  void observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
               const Eigen::Ref<const Eigen::ArrayXd>& velocity,
               const Eigen::Ref<const Eigen::ArrayXd>& load);
  void reset() { next_ = 0; }
  bool due(std::int64_t n) const { return next_ < steps_.size() && steps_[next_] == n; }

  const std::vector<std::int64_t>& steps() const { return steps_; }
  // Column k holds the lanes' values at steps()[k].
  const Eigen::ArrayXXd& delta() const { return delta_; }
  const Eigen::ArrayXXd& velocity() const { return velocity_; }
  const Eigen::ArrayXXd& load() const { return load_; }
  std::size_t taken() const { return next_; }

 private:
  std::vector<std::int64_t> steps_;
  std::size_t next_ = 0;
  Eigen::ArrayXXd delta_, velocity_, load_;
};

// True when t / h is a whole number to 1e-9 (t lies on the integration grid).
bool on_step_grid(double t, double h);

// Interpolation inside one step [t_n, t_n + h] at t_n + s h, 0 <= s <= 1 (the Poincare sections of
// doc/nonlinear-dynamics.md §3): cubic Hermite for a state x with its derivative v = dx/dt at both
// ends (error O(h^4)), linear for a state without one (error O(h^2)).
double hermite_in_step(double x0, double v0, double x1, double v1, double s, double h);
// The cubic Hermite's time derivative: x's rate between grid points, O(h^3) where a straight line
// between the end rates errs at O(h^2) (a contact oscillation at omega h = 0.13: 1.6e-5 against
// 2e-3 of its amplitude).
double hermite_slope_in_step(double x0, double v0, double x1, double v1, double s, double h);
double linear_in_step(double x0, double x1, double s);

// One point of a Poincare section: (delta, delta_dot) at time t.
struct SectionPoint {
  double time = 0;       // t_k [s]
  double delta = 0;      // [m]
  double delta_dot = 0;  // [m/s]
};

// (delta, delta_dot) of every lane at t_k = offset + k period, k = 0, 1, ..., t_k <= end (a Poincare
// section at a fixed mesh phase, doc/nonlinear-dynamics.md §3), from the grid states it is shown
// one after the other. If offset and period are whole numbers of steps (to 1e-9 of a step) the
// points are grid states, exactly; otherwise each point is interpolated in its step, cubic Hermite
// in delta (slopes delta_dot) and that cubic's slope for delta_dot: the definition and the arithmetic of the
// core's poincare_section (dynamics/poincare.hpp), so both give the same numbers, bit for bit.
class PoincareSampler {
 public:
  PoincareSampler(int lanes, double time_step, double period, double offset, double end);
  // Grid step n (from n = 0, in order, one after the other) and the lanes' state there.
  void observe(std::int64_t n, const Eigen::Ref<const Eigen::ArrayXd>& delta,
               const Eigen::Ref<const Eigen::ArrayXd>& velocity);
  const std::vector<std::vector<SectionPoint>>& points() const { return points_; }  // per lane, in time order

 private:
  void emit(double t, const Eigen::Ref<const Eigen::ArrayXd>& delta, const Eigen::Ref<const Eigen::ArrayXd>& velocity,
            bool grid, double s);
  double h_, period_, offset_, end_;
  bool exact_;
  std::int64_t m_, n0_, k_ = 0;
  bool due_ = false;      // t_k lies in the step that follows the last observed one
  double t_prev_ = 0;     // time of the grid point before t_k (interpolated points)
  Eigen::ArrayXd delta_prev_, velocity_prev_;
  std::vector<std::vector<SectionPoint>> points_;
};

}  // namespace gear_dynamics
