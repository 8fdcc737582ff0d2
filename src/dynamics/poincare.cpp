#include "gear_dynamics/dynamics/poincare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace gear_dynamics {

std::vector<SectionState> poincare_section(LaneSystem& sys, const PoincareOptions& o,
                                            const std::function<void(const LaneSystem&)>& after_step) {
  const double h = sys.time_step();
  const int lanes = sys.lanes(), dim = sys.dimension();
  std::vector<double> period = o.lane_period;
  if (period.empty()) period.assign(lanes, o.period);
  if (static_cast<int>(period.size()) != lanes) throw std::invalid_argument("poincare_section: one period per lane");
  for (double p : period)
    if (!(p > 0)) throw std::invalid_argument("poincare_section: period must be > 0");
  const std::int64_t n_end = static_cast<std::int64_t>(std::llround(o.end / h));
  // Per lane: exact (grid) sampling at steps n0 + k m, or interpolated at offset + k period.
  struct LaneState {
    bool exact;
    std::int64_t m, n0, k;
    double next;  // interpolated: t_k
  };
  std::vector<LaneState> ls(lanes);
  const bool offset_on_grid = on_step_grid(o.offset, h);
  const double t_begin = std::max(o.start, sys.time());
  for (int l = 0; l < lanes; ++l) {
    LaneState& L = ls[l];
    L.exact = offset_on_grid && on_step_grid(period[l], h);
    L.m = std::llround(period[l] / h);
    L.n0 = std::llround(o.offset / h);
    L.k = static_cast<std::int64_t>(std::ceil((t_begin - o.offset) / period[l] - 1e-9));
    if (L.k < 0) L.k = 0;
    if (L.exact)
      while (L.n0 + L.k * L.m < sys.step_index() || static_cast<double>(L.n0 + L.k * L.m) * h < o.start - 1e-9 * h) ++L.k;
    L.next = o.offset + static_cast<double>(L.k) * period[l];
  }
  std::vector<SectionState> out;
  std::vector<double> prev(static_cast<std::size_t>(lanes * dim));
  std::vector<char> due(lanes, 0);
  const auto emit = [&](int l, double t, bool grid, double s) {
    SectionState p;
    p.lane = l;
    p.k = ls[l].k;
    p.time = t;
    p.on_grid = grid;
    p.x.resize(dim);
    for (int c = 0; c < dim; ++c) {
      const double x1 = sys.state(l, c);
      if (grid) { p.x[c] = x1; continue; }
      const double x0 = prev[l * dim + c];
      const int dc = sys.derivative_of(c);
      // Cubic Hermite on [t_n, t_n + h] with slopes from the derivative component; a derivative
      // component takes that cubic's slope; any other, a straight line: the batch's
      // PoincareSampler (engine/observers.hpp) calls the same functions.
      int integral = -1;
      for (int q = 0; q < dim; ++q)
        if (sys.derivative_of(q) == c) integral = q;
      if (dc >= 0)
        p.x[c] = hermite_in_step(x0, prev[l * dim + dc], x1, sys.state(l, dc), s, h);
      else if (integral >= 0)
        p.x[c] = hermite_slope_in_step(prev[l * dim + integral], x0, sys.state(l, integral), x1, s, h);
      else
        p.x[c] = linear_in_step(x0, x1, s);
    }
    out.push_back(std::move(p));
    ++ls[l].k;
  };
  for (;;) {
    const std::int64_t n = sys.step_index();
    for (int l = 0; l < lanes; ++l)
      if (ls[l].exact && n == ls[l].n0 + ls[l].k * ls[l].m) emit(l, static_cast<double>(n) * h, true, 1.0);
    if (n >= n_end) break;
    const double t0 = sys.time();
    for (int l = 0; l < lanes; ++l) {
      due[l] = 0;
      if (ls[l].exact) continue;
      ls[l].next = o.offset + static_cast<double>(ls[l].k) * period[l];
      if (ls[l].next <= t0 + h && ls[l].next <= o.end) {
        due[l] = 1;
        for (int c = 0; c < dim; ++c) prev[l * dim + c] = sys.state(l, c);
      }
    }
    sys.step();
    if (after_step) after_step(sys);
    for (int l = 0; l < lanes; ++l)
      if (due[l]) emit(l, ls[l].next, false, (ls[l].next - t0) / h);
  }
  // Points in time order, lanes in order within one instant.
  std::stable_sort(out.begin(), out.end(), [](const SectionState& a, const SectionState& b) {
    return a.time < b.time || (a.time == b.time && a.lane < b.lane);
  });
  return out;
}

}  // namespace gear_dynamics
