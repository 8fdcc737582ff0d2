// Ensemble::step's lanes (engine/ensemble.hpp): the kernel (engine/rk4_kernel.hpp) on the padded
// arrays, in packets of Ensemble::kPacket; and Realization::step's one lane (the same kernel on
// doubles). Compiled once per instruction set.
#include "variant.hpp"

#include <cmath>
#include <type_traits>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"

namespace gear_dynamics::GD_ISA_NAMESPACE {

bool ensemble_step(const dispatch::EnsembleStep& s) {
  constexpr int kPacket = Ensemble::kPacket;
  using Packet = Eigen::Array<double, kPacket, 1>;
  const StepPlan plan = s.mesh->plan(s.n);
  const double h = s.h, sqrt_h = s.sqrt_h, b = s.backlash, alpha = s.alpha, q3 = s.q3;
  Packet sum = Packet::Zero();  // NaN and inf propagate through it: one finiteness test per step

  // N lanes at a time: N = 4 kPacket (a default block of 32 lanes) runs four packets' dependency
  // chains side by side in each statement (the kernel is latency-bound: more chains hide more of
  // it), what is left two packets or one at a time.
  const auto step_lanes = [&](auto lanes, std::ptrdiff_t p) GD_KERNEL_INLINE_LAMBDA {
    constexpr int N = decltype(lanes)::value;
    using Lanes = Eigen::Array<double, N, 1>;
    using In = Eigen::Map<const Lanes>;
    using Out = Eigen::Map<Lanes>;
    Lanes d = In(s.delta + p);
    Lanes v = In(s.velocity + p);
    const Lanes load0 = In(s.load + p);
    const Lanes mu = In(s.mu + p);
    const Lanes z = In(s.z + p);
    // The kernel shared with the one-lane path (Realization): the same operations per lane.
    const Lanes load1 = kernel::load_next<Lanes>(load0, Lanes(In(s.drift + p)), Lanes(In(s.sigma + p)), z, h, sqrt_h);
    kernel::rk4_step<Lanes>(plan, h, b, alpha, q3, mu, load0, load1, d, v);
    Out(s.delta + p) = d;
    Out(s.velocity + p) = v;
    Out(s.load + p) = load1;
    const Lanes dv = d + v;
    for (int k = 0; k < N; k += kPacket) sum += dv.template segment<kPacket>(k);  // packet by packet, in order
  };
  std::ptrdiff_t p = 0;
  for (; p + 4 * kPacket <= s.lanes; p += 4 * kPacket) step_lanes(std::integral_constant<int, 4 * kPacket>{}, p);
  for (; p + 2 * kPacket <= s.lanes; p += 2 * kPacket) step_lanes(std::integral_constant<int, 2 * kPacket>{}, p);
  if (p < s.lanes) step_lanes(std::integral_constant<int, kPacket>{}, p);
  return std::isfinite(sum.sum());
}

void realization_step(const dispatch::RealizationStep& s) {
  const StepPlan plan = s.mesh->plan(s.n);
  const double load0 = *s.load;
  const double load1 = kernel::load_next<double>(load0, s.drift, s.sigma, s.z, s.h, s.sqrt_h);
  double d = *s.delta, v = *s.velocity;
  kernel::rk4_step<double>(plan, s.h, s.backlash, s.alpha, s.q3, s.mu, load0, load1, d, v);
  *s.delta = d;
  *s.velocity = v;
  *s.load = load1;
}

}  // namespace gear_dynamics::GD_ISA_NAMESPACE
