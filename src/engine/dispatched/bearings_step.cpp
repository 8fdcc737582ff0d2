// Ensemble::step's lanes of the bearings model (engine/bearings.hpp), in packets of
// Ensemble::kPacket as the torsional kernel's (ensemble_step.cpp): every lane first takes the branch
// RK4 step of its segment in SIMD (BearingsModel's lane derivative, the scalar path's expressions in
// its order); lanes whose step may have met a boundary are redone by the located segment
// (model_step::located_segment, bearings_step's path), one by one. Compiled once per instruction set.
#include "variant.hpp"

#include <cmath>
#include <tuple>
#include <type_traits>

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/model_step.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"

namespace gear_dynamics::GD_ISA_NAMESPACE {

namespace {

constexpr int kStates = BearingsModel::kStates;
using M = BearingsModel;

// What bearings_step derives from a plan segment for every lane alike.
struct SegmentMesh {
  double H, e_dot, error_mid;
  double share_start, share_mid, share_end;  // friction_share at the stage times (sigma, per unit mu)
};

template <int N>
using Lanes = Eigen::Array<double, N, 1>;

template <int N>
GD_KERNEL_INLINE Lanes<N> deflection(const Lanes<N>* y) {
  return (y[M::kDelta] + y[M::kPinionY]) - y[M::kWheelY];
}
template <int N>
GD_KERNEL_INLINE Lanes<N> deflection_rate(const Lanes<N>* y) {
  return (y[M::kDeltaDot] + y[M::kPinionYDot]) - y[M::kWheelYDot];
}

// bearings_step's friction force per unit mesh force: mu sigma, 0 where mu is 0.
template <int N>
GD_KERNEL_INLINE Lanes<N> friction_force(const Lanes<N>& mu, double share) {
  return (mu == 0.0).select(Lanes<N>::Zero(), mu * share);
}

// The segment of grid step n on N lanes from y (in place): model_step::located_segment's whole branch
// step in SIMD, the located segment for the lanes near a boundary.
template <int N>
GD_KERNEL_INLINE void segment_lanes(const M& model, const StepSegment& seg, const SegmentMesh& m, double q3,
                                    const Lanes<N>& mu, const Lanes<N>& load0, const Lanes<N>& load1, Lanes<N>* y) {
  using P = Lanes<N>;
  const double H = m.H, b = model.backlash(), ea = seg.error_start, eb = seg.error_end;
  const kernel::SegmentLoads<P> l = kernel::segment_loads<P>(seg, q3, mu, load0, load1);
  const M::LanePoint<P> p0{seg.stiffness_start, l.qa, friction_force(mu, m.share_start), l.la, ea, m.e_dot};
  const M::LanePoint<P> pm{seg.stiffness_mid, l.qm, friction_force(mu, m.share_mid), P(0.5 * (l.la + l.lb)),
                           m.error_mid, m.e_dot};
  const M::LanePoint<P> p1{seg.stiffness_end, l.qb, friction_force(mu, m.share_end), l.lb, eb, m.e_dot};
  P y0[kStates];
  for (int k = 0; k < kStates; ++k) y0[k] = y[k];
  // The branch each lane starts on (kernel::branch_of of delta_m - e).
  const P x = deflection(y0) - ea;
  const P side = (x > b).template cast<double>() - (x < -b).template cast<double>();
  const P contact = side * side;
  // model_step::detail::branch_rk4: y + half k1, y + half k2, y + H k3, then
  // y + (H / 6) (k1 + 2 k2 + 2 k3 + k4), component by component.
  const double half = 0.5 * H;
  P k1[kStates], k2[kStates], k3[kStates], k4[kStates], ys[kStates];
  model.derivative(side, contact, y0, p0, k1);
  for (int k = 0; k < kStates; ++k) ys[k] = y0[k] + half * k1[k];
  model.derivative(side, contact, ys, pm, k2);
  for (int k = 0; k < kStates; ++k) ys[k] = y0[k] + half * k2[k];
  model.derivative(side, contact, ys, pm, k3);
  for (int k = 0; k < kStates; ++k) ys[k] = y0[k] + H * k3[k];
  model.derivative(side, contact, ys, p1, k4);
  for (int k = 0; k < kStates; ++k) y[k] = y0[k] + (H / 6.0) * (((k1[k] + 2.0 * k2[k]) + 2.0 * k3[k]) + k4[k]);

  // The crossing search keeps this step where the step's cubic Hermite dense output of delta_m stays
  // off +-b + e: its band [min, max] of the end values, widened by the most the Hermite overshoots
  // them (4/27 (|m0| + |m1|), taken as 1/4) and by a billionth of b for the search's roundings,
  // shifted by e over the segment (kernel::boundary_proximity without the stages: the branch step is
  // taken on the start branch whatever its stages see).
  const P d0 = deflection(y0), d1 = deflection(y);
  const P reach = P((0.25 * H) * P(deflection_rate(y0).abs() + deflection_rate(y).abs())) + 1e-9 * b;
  const double spread = std::fabs(eb - ea);
  const P lo = P(P(d0.min(d1) - reach) - (ea + spread));
  const P hi = P(P(d0.max(d1) + reach) - (ea - spread));
  const P near = P((lo - b) * (hi - b)).min(P((lo + b) * (hi + b)));
  if (!(near.minCoeff() <= 0.0)) return;
  for (int i = 0; i < N; ++i) {
    if (!(near[i] <= 0.0)) continue;
    // bearings_step's segment of this lane.
    const model_step::Segment s{H,
                                b,
                                {p0.stiffness, p0.q[i], p0.friction_force[i], p0.load[i], p0.error, p0.error_rate},
                                {pm.stiffness, pm.q[i], pm.friction_force[i], pm.load[i], pm.error, pm.error_rate},
                                {p1.stiffness, p1.q[i], p1.friction_force[i], p1.load[i], p1.error, p1.error_rate}};
    M::State yi;
    for (int k = 0; k < kStates; ++k) yi[k] = y0[k][i];
    model_step::located_segment(model, s, yi);
    for (int k = 0; k < kStates; ++k) y[k][i] = yi[k];
  }
}

}  // namespace

bool bearings_ensemble_step(const dispatch::BearingsEnsembleStep& s) {
  constexpr int kPacket = Ensemble::kPacket;
  const M& model = *s.model;
  const GearPair& gear = *s.gear;
  const StepPlan plan = s.mesh->plan(s.n);
  const double h = s.h, sqrt_h = s.sqrt_h, q3 = gear.q3;
  // The segments' mesh, the same for every lane (bearings_step's: sigma a billionth of the segment
  // inside it, on its side of a jump); sigma only where some lane has friction.
  bool friction = false;
  for (std::ptrdiff_t i = 0; i < s.lanes; ++i) friction = friction || s.mu[i] != 0.0;
  const double speed = gear.in.pinion_speed, a_start = gear.in.mesh_phase + speed * static_cast<double>(s.n) * h;
  const MeshTable* table = s.mesh->table();
  const auto share = [&](double u) { return friction ? friction_share(gear, table, a_start + speed * h * u) : 0.0; };
  SegmentMesh mesh[std::tuple_size_v<decltype(plan.segment)>];
  for (int k = 0; k < plan.segments; ++k) {
    const StepSegment& seg = plan.segment[k];
    const double H = (seg.end - seg.begin) * h, inset = 1e-9 * (seg.end - seg.begin);
    mesh[k] = {H,
               (seg.error_end - seg.error_start) / H,
               0.5 * (seg.error_start + seg.error_end),
               share(seg.begin + inset),
               share(0.5 * (seg.begin + seg.end)),
               share(seg.end - inset)};
  }
  Eigen::Array<double, kPacket, 1> sum = Eigen::Array<double, kPacket, 1>::Zero();
  const auto step_lanes = [&](auto width, std::ptrdiff_t p) GD_KERNEL_INLINE_LAMBDA {
    constexpr int N = decltype(width)::value;
    using P = Lanes<N>;
    using In = Eigen::Map<const P>;
    P y[kStates];
    for (int k = 0; k < kStates; ++k) y[k] = In(s.state + k * s.stride + p);
    const P load0 = In(s.load + p), mu = In(s.mu + p);
    // BearingsRealization::step's load step.
    const P load1 = kernel::load_next<P>(load0, P(In(s.drift + p)), P(In(s.sigma + p)), P(In(s.z + p)), h, sqrt_h);
    for (int k = 0; k < plan.segments; ++k) segment_lanes<N>(model, plan.segment[k], mesh[k], q3, mu, load0, load1, y);
    P total = P::Zero();
    for (int k = 0; k < kStates; ++k) {
      Eigen::Map<P>(s.state + k * s.stride + p) = y[k];
      total += y[k];
    }
    Eigen::Map<P>(s.delta + p) = deflection(y);
    Eigen::Map<P>(s.velocity + p) = deflection_rate(y);
    Eigen::Map<P>(s.load + p) = load1;
    for (int k = 0; k < N; k += kPacket) sum += total.template segment<kPacket>(k);  // NaN and inf propagate
  };
  std::ptrdiff_t p = 0;
  for (; p + 2 * kPacket <= s.lanes; p += 2 * kPacket) step_lanes(std::integral_constant<int, 2 * kPacket>{}, p);
  if (p < s.lanes) step_lanes(std::integral_constant<int, kPacket>{}, p);
  return std::isfinite(sum.sum());
}

}  // namespace gear_dynamics::GD_ISA_NAMESPACE
