#include "gear_dynamics/dynamics/system.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/rk4_kernel.hpp"

namespace gear_dynamics {

BearingsLanes::BearingsLanes(Ensemble& ensemble) : e_(ensemble) {
  if (!ensemble.bearings_model())
    throw std::invalid_argument("BearingsLanes: the ensemble runs gear_pair.model = torsional; allowed: bearings");
}

int BearingsLanes::dimension() const { return BearingsModel::kStates; }

// Each displacement's rate follows it in BearingsModel::Index (delta, delta_dot, x_p, x_p_dot, ...).
int BearingsLanes::derivative_of(int c) const { return c % 2 == 0 ? c + 1 : -1; }

GearLanes::GearLanes(const std::vector<GearLaneSpec>& lanes, double time_step) : h_(time_step) {
  if (lanes.empty()) throw std::invalid_argument("GearLanes: needs at least one lane");
  const int n = static_cast<int>(lanes.size());
  const int p = (n + Ensemble::kPacket - 1) / Ensemble::kPacket * Ensemble::kPacket;
  for (Eigen::ArrayXd* a : {&d_, &v_, &load_, &mu_, &q3_, &b_, &alpha_, &ka_, &km_, &kb_, &fa_, &fm_, &fb_, &ea_, &eb_}) a->setZero(p);
  b_.setOnes();  // padding lanes rest at 0, far from their boundaries: never located
  lane_.reserve(lanes.size());
  plan_.resize(lanes.size());
  for (int i = 0; i < n; ++i) {
    const GearLaneSpec& s = lanes[i];
    const GearPair g = derive(s.gear);
    lane_.push_back(Lane{g, MeshSchedule(g, time_step)});
    d_[i] = s.initial.deflection;
    v_[i] = s.initial.velocity;
    load_[i] = s.load;
    mu_[i] = s.mu;
    q3_[i] = g.q3;
    b_[i] = g.in.backlash;
    alpha_[i] = g.damping_coefficient;
  }
}

// Ensemble::step() for sigma = drift = 0 through the same kernel: load0 = load1, so every stage load
// is the lane's load.
void GearLanes::step_lane(int i, const StepPlan& plan) {
  double d = d_[i], v = v_[i];
  kernel::rk4_step<double>(plan, h_, b_[i], alpha_[i], q3_[i], mu_[i], load_[i], load_[i], d, v);
  d_[i] = d;
  v_[i] = v;
}

// The lanes' plans are made one by one; packets of lanes whose steps are all unsplit (2999 steps in
// 3000) are stepped as SIMD packets with the same operations in the same order as the scalar path
// (and as the Ensemble), the others lane by lane.
void GearLanes::step() {
  using Packet = Eigen::Array<double, Ensemble::kPacket, 1>;
  const int n = lanes();
  for (int i = 0; i < n; ++i) plan_[i] = lane_[i].mesh.plan(n_);
  for (int p0 = 0; p0 < n; p0 += Ensemble::kPacket) {
    const int p1 = std::min(n, p0 + Ensemble::kPacket);
    bool simple = true;
    for (int i = p0; i < p1; ++i) simple = simple && plan_[i].segments == 1;
    if (!simple) {
      for (int i = p0; i < p1; ++i) step_lane(i, plan_[i]);
      continue;
    }
    for (int i = p0; i < p1; ++i) {
      const StepSegment& seg = plan_[i].segment[0];
      ka_[i] = seg.stiffness_start;
      km_[i] = seg.stiffness_mid;
      kb_[i] = seg.stiffness_end;
      ea_[i] = seg.error_start;
      eb_[i] = seg.error_end;
      fa_[i] = seg.friction_start;
      fm_[i] = seg.friction_mid;
      fb_[i] = seg.friction_end;
    }
    const auto seg = [&](const Eigen::ArrayXd& a) { return Packet(a.segment<Ensemble::kPacket>(p0)); };
    const Packet b = seg(b_), alpha = seg(alpha_), q3 = seg(q3_), mu = seg(mu_), load = seg(load_);
    const Packet qa = kernel::fused_mul_add(mu, seg(fa_), q3), qm = kernel::fused_mul_add(mu, seg(fm_), q3),
                 qb = kernel::fused_mul_add(mu, seg(fb_), q3);
    Packet d = seg(d_), v = seg(v_);
    // rk4_step's unsplit segment: H = (1 - 0) h, the load constant.
    kernel::rk4_segment<Packet, Packet>(h_, seg(ka_), seg(km_), seg(kb_), b, alpha, qa, qm, qb, load, load, seg(ea_),
                                        seg(eb_), d, v);
    d_.segment<Ensemble::kPacket>(p0) = d;
    v_.segment<Ensemble::kPacket>(p0) = v;
  }
  ++n_;
}

LinearOscillatorLanes::LinearOscillatorLanes(const std::vector<LinearOscillatorParams>& lanes, double time_step,
                                             const std::vector<double>& x0, const std::vector<double>& v0)
    : p_(lanes), x_(2 * lanes.size()), h_(time_step) {
  if (x0.size() != lanes.size() || v0.size() != lanes.size())
    throw std::invalid_argument("LinearOscillatorLanes: one initial state per lane");
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    x_[2 * i] = x0[i];
    x_[2 * i + 1] = v0[i];
  }
}

void LinearOscillatorLanes::step() {
  const double t = time(), h = h_;
  for (std::size_t i = 0; i < p_.size(); ++i) {
    const LinearOscillatorParams& p = p_[i];
    const auto acc = [&](double tt, double x, double v) {
      return p.force * std::cos(p.forcing_frequency * tt) - 2.0 * p.zeta * p.omega * v - p.omega * p.omega * x;
    };
    const double x = x_[2 * i], v = x_[2 * i + 1];
    const double a1 = acc(t, x, v);
    const double a2 = acc(t + 0.5 * h, x + 0.5 * h * v, v + 0.5 * h * a1);
    const double v2 = v + 0.5 * h * a1;
    const double v3 = v + 0.5 * h * a2;
    const double a3 = acc(t + 0.5 * h, x + 0.5 * h * v2, v3);
    const double v4 = v + h * a3;
    const double a4 = acc(t + h, x + h * v3, v4);
    x_[2 * i] = x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
    x_[2 * i + 1] = v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
  }
  ++n_;
}

void LinearOscillatorLanes::steady_state(const LinearOscillatorParams& p, double t, double& x, double& v) {
  // X = F / (omega^2 - w^2 + 2 i zeta omega w); x = Re(X e^{i w t}).
  const double w = p.forcing_frequency;
  const double re = p.omega * p.omega - w * w, im = 2.0 * p.zeta * p.omega * w;
  const double den = re * re + im * im;
  const double Xr = p.force * re / den, Xi = -p.force * im / den;
  const double c = std::cos(w * t), s = std::sin(w * t);
  x = Xr * c - Xi * s;
  v = w * (-Xr * s - Xi * c);
}

LorenzLanes::LorenzLanes(const LorenzParams& p, double time_step, const std::vector<std::vector<double>>& initial)
    : p_(p), h_(time_step) {
  for (const auto& x : initial) {
    if (x.size() != 3) throw std::invalid_argument("LorenzLanes: a state has 3 components");
    x_.insert(x_.end(), x.begin(), x.end());
  }
  if (x_.empty()) throw std::invalid_argument("LorenzLanes: needs at least one lane");
}

void LorenzLanes::step() {
  const double h = h_;
  const auto f = [&](const double* x, double* dx) {
    dx[0] = p_.sigma * (x[1] - x[0]);
    dx[1] = x[0] * (p_.rho - x[2]) - x[1];
    dx[2] = x[0] * x[1] - p_.beta * x[2];
  };
  for (std::size_t i = 0; i < x_.size(); i += 3) {
    double* x = &x_[i];
    double k1[3], k2[3], k3[3], k4[3], y[3];
    f(x, k1);
    for (int c = 0; c < 3; ++c) y[c] = x[c] + 0.5 * h * k1[c];
    f(y, k2);
    for (int c = 0; c < 3; ++c) y[c] = x[c] + 0.5 * h * k2[c];
    f(y, k3);
    for (int c = 0; c < 3; ++c) y[c] = x[c] + h * k3[c];
    f(y, k4);
    for (int c = 0; c < 3; ++c) x[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
  }
  ++n_;
}

}  // namespace gear_dynamics
