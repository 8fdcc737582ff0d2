#include "gear_dynamics/model/tooth_stiffness.hpp"

#include <boost/math/special_functions/legendre.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace gear_dynamics {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Sainsot, Velex & Duverger (2004), Table 1: X* = A/theta_f^2 + B h_f^2 + C h_f/theta_f + D/theta_f
// + E h_f + F for X = L, M, P, Q, with h_f = r_f / r_int.
struct FoundationCoefficients {
  double A, B, C, D, E, F;
  double at(double h, double theta) const {
    return A / (theta * theta) + B * h * h + C * h / theta + D / theta + E * h + F;
  }
};
constexpr FoundationCoefficients kSainsotL{-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045};
constexpr FoundationCoefficients kSainsotM{60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086};
constexpr FoundationCoefficients kSainsotP{-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236};
constexpr FoundationCoefficients kSainsotQ{-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904};

// One gear's tooth as a cantilever on the gear body (Tian 2004; Chen & Shao 2011): the involute from
// the base circle (or from the root circle, where that lies above it) to the tip, and, where the
// root circle lies below the base circle, a straight part of the base circle's thickness between
// them. In the tooth's frame y runs along the centre line from the gear's centre and x across it;
// the involute point of parameter tau is x = rb ((tau + theta_b) cos tau - sin tau),
// y = rb ((tau + theta_b) sin tau + cos tau), and the contact force at roll length s = sqrt(r^2 - rb^2)
// acts at tau_c = s / rb - theta_b, at the angle tau_c to the x axis.
struct Tooth {
  double rb, rf, theta_b, theta_f, bore, E, G, nu, L;
  double tau_start;  // the involute's first point on the tooth
  double y_straight; // the straight part runs from rf to here (rf itself: none)
  // A root crack: the half-thickness kept beyond the crack's tip, h_q, and the parameter tau at
  // which the involute's half-thickness falls to h_q (the crack shields the sections below it).
  bool cracked = false;
  double h_q = 0.0, tau_crack = 0.0;

  double x(double tau) const { return rb * ((tau + theta_b) * std::cos(tau) - std::sin(tau)); }
  double y(double tau) const { return rb * ((tau + theta_b) * std::sin(tau) + std::cos(tau)); }
  double dy(double tau) const { return rb * (tau + theta_b) * std::cos(tau); }
};

Tooth make_tooth(double rb, double rf, int z, double alpha0, double shift, double ha, double hf, double bore,
                 double E, double nu, double L) {
  Tooth t;
  t.rb = rb, t.rf = rf, t.bore = bore, t.E = E, t.nu = nu, t.L = L, t.G = E / (2.0 * (1.0 + nu));
  const double inv = std::tan(alpha0) - alpha0;
  t.theta_b = kPi / (2.0 * z) + 2.0 * shift * std::tan(alpha0) / z + inv;
  // Half the tooth's angle at the root circle with the rack cutter's tip radius rho
  // (c = hf - ha the clearance coefficient), as in Sainsot's formula's derivation.
  const double c = hf - ha, rho = c / (1.0 - std::sin(alpha0));
  t.theta_f = (kPi / 2.0 + 2.0 * shift * std::tan(alpha0) + 2.0 * std::tan(alpha0) * (ha - rho) +
               2.0 * rho / std::cos(alpha0)) / z;
  if (rf > rb) {
    t.tau_start = std::sqrt(rf * rf - rb * rb) / rb - t.theta_b;
    t.y_straight = rf;
  } else {
    t.tau_start = -t.theta_b;
    t.y_straight = std::max(rf, rb * std::cos(t.theta_b));
  }
  return t;
}

// Bending, shear and axial compliances [m/N] of the tooth loaded at tau_c, by Gauss-Legendre on
// each smooth part (the straight part, the involute below and above the crack's reach).
void tooth_compliance(const Tooth& t, double tau_c, const std::vector<double>& nodes,
                      const std::vector<double>& weights, double& bending, double& shear, double& axial) {
  const double ca = std::cos(tau_c), sa = std::sin(tau_c);
  const double xc = t.x(tau_c), yc = t.y(tau_c);
  bending = shear = axial = 0.0;
  // Energies per unit force squared of a section of half-thickness h (h_q + h: cracked) at y.
  const auto add = [&](double y, double h, bool cracked, double w) {
    const double width = cracked ? h + t.h_q : 2.0 * h;  // the section's thickness
    const double A = width * t.L, I = width * width * width * t.L / 12.0;
    const double M = ca * (yc - y) - sa * xc;
    bending += w * M * M / (t.E * I);
    shear += w * 1.2 * ca * ca / (t.G * A);
    axial += w * sa * sa / (t.E * A);
  };
  const auto gauss = [&](double a, double b, auto&& f) {
    if (!(b > a)) return;
    const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
    for (std::size_t k = 0; k < nodes.size(); ++k) f(mid + half * nodes[k], half * weights[k]);
  };
  if (t.y_straight > t.rf) {  // below the involute: the crack (from the root) cuts it all
    const double h = t.rb * std::sin(t.theta_b);
    gauss(t.rf, t.y_straight, [&](double y, double w) { add(y, h, t.cracked, w); });
  }
  const double split = t.cracked ? std::min(std::max(t.tau_crack, t.tau_start), tau_c) : t.tau_start;
  gauss(t.tau_start, split, [&](double tau, double w) { add(t.y(tau), t.x(tau), true, w * t.dy(tau)); });
  gauss(split, tau_c, [&](double tau, double w) { add(t.y(tau), t.x(tau), false, w * t.dy(tau)); });
}

// Sainsot's fillet-foundation compliance [m/N] for a load at tau_c.
double foundation_compliance(const Tooth& t, double tau_c) {
  const double h = t.rf / t.bore, theta = t.theta_f;
  const double uf = t.y(tau_c) - t.rf, sf = 2.0 * t.rf * theta;
  const double c = std::cos(tau_c), tn = std::tan(tau_c);
  return c * c / (t.E * t.L) *
         (kSainsotL.at(h, theta) * (uf / sf) * (uf / sf) + kSainsotM.at(h, theta) * (uf / sf) +
          kSainsotP.at(h, theta) * (1.0 + kSainsotQ.at(h, theta) * tn * tn));
}

}  // namespace

struct ToothPairStiffness::Geometry {
  Tooth tooth[2];
  int crack_gear = -1, spall_gear = -1;  // 0 pinion, 1 wheel, -1 none
  double spall_lo = 0.0, spall_hi = 0.0;  // the spall's extent in x [m]
};

ToothPairStiffness::ToothPairStiffness(const GearPair& gear, PotentialEnergyOptions options)
    : gear_(gear), options_(options) {
  if (options.quadrature_points < 2 || options.quadrature_points > 512)
    throw std::invalid_argument("ToothPairStiffness: quadrature_points = " + std::to_string(options.quadrature_points) +
                                " is out of range; allowed [2, 512]");
  // Gauss-Legendre on [-1, 1]: Boost's positive zeros of P_n, mirrored, with w = 2 / ((1 - x^2) P_n'(x)^2).
  const int n = options.quadrature_points;
  for (double x : boost::math::legendre_p_zeros<double>(n)) {
    const double d = boost::math::legendre_p_prime<double>(n, x);
    const double w = 2.0 / ((1.0 - x * x) * d * d);
    nodes_.push_back(x), weights_.push_back(w);
    if (x != 0.0) nodes_.push_back(-x), weights_.push_back(w);
  }
  const GearInputs& in = gear.in;
  auto g = std::make_shared<Geometry>();
  g->tooth[0] = make_tooth(gear.base_radius1, gear.root_radius1, in.pinion_teeth, in.pressure_angle, in.profile_shift1,
                           in.addendum_coefficient, in.dedendum_coefficient, in.bore_radius1, in.youngs_modulus,
                           in.poisson_ratio, in.face_width);
  g->tooth[1] = make_tooth(gear.base_radius2, gear.root_radius2, in.gear_teeth, in.pressure_angle, in.profile_shift2,
                           in.addendum_coefficient, in.dedendum_coefficient, in.bore_radius2, in.youngs_modulus,
                           in.poisson_ratio, in.face_width);
  if (in.crack.gear != FaultyGear::kNone && in.crack.depth > 0.0) {
    g->crack_gear = in.crack.gear == FaultyGear::kPinion ? 0 : 1;
    Tooth& t = g->tooth[g->crack_gear];
    // The crack starts at the root of the loaded side and runs inwards at upsilon to the centre
    // line (Wu, Zuo & Parey 2008; Chaari et al. 2009): the sections from the root up to where the
    // tooth's half-thickness falls to the crack tip's distance h_q from the centre line carry the
    // load on h_q + h only.
    t.cracked = true;
    t.h_q = t.x(t.tau_start) - in.crack.depth * std::sin(in.crack.angle);
    // The involute's half-thickness falls with tau: the sections up to where it reaches h_q are cut.
    const double tip = g->crack_gear ? gear.tip_radius2 : gear.tip_radius1;
    double lo = t.tau_start, hi = std::sqrt(tip * tip - t.rb * t.rb) / t.rb - t.theta_b;
    if (t.x(hi) >= t.h_q) {
      lo = hi;  // the whole tooth up to its tip is shielded
    } else {
      for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        (t.x(mid) > t.h_q ? lo : hi) = mid;
      }
    }
    t.tau_crack = lo;
  }
  if (in.spall.gear != FaultyGear::kNone && in.spall.length > 0.0 && in.spall.width > 0.0) {
    g->spall_gear = in.spall.gear == FaultyGear::kPinion ? 0 : 1;
    const double rb = g->spall_gear ? gear.base_radius2 : gear.base_radius1;
    const double roll = std::sqrt(std::max(0.0, in.spall.position * in.spall.position - rb * rb));
    const double centre = g->spall_gear ? gear.line_of_centres_length - roll : roll;
    g->spall_lo = centre - 0.5 * in.spall.length;
    g->spall_hi = centre + 0.5 * in.spall.length;
  }
  geometry_ = std::move(g);
}

PairCompliance ToothPairStiffness::compliance(double x, int pinion_tooth, int wheel_tooth) const {
  const GearInputs& in = gear_.in;
  const Geometry& g = *geometry_;
  PairCompliance c;
  const double roll[2] = {x, gear_.line_of_centres_length - x};
  const int index[2] = {pinion_tooth, wheel_tooth};
  for (int k = 0; k < 2; ++k) {
    Tooth t = g.tooth[k];
    t.cracked = t.cracked && index[k] == in.crack.tooth;
    const double tau_c = roll[k] / t.rb - t.theta_b;
    tooth_compliance(t, tau_c, nodes_, weights_, c.bending[k], c.shear[k], c.axial[k]);
    c.foundation[k] = options_.fillet_foundation ? foundation_compliance(t, tau_c) : 0.0;
  }
  // Hertz (Yang & Lin 1987): a constant over the contact, on the width that touches: a spall takes
  // its width out while the contact crosses it.
  double width = in.face_width;
  if (g.spall_gear >= 0 && index[g.spall_gear] == in.spall.tooth && x >= g.spall_lo && x < g.spall_hi)
    width -= in.spall.width;
  c.hertz = 4.0 * (1.0 - in.poisson_ratio * in.poisson_ratio) / (kPi * in.youngs_modulus * width);
  return c;
}

std::vector<double> ToothPairStiffness::discontinuities(int pinion_tooth, int wheel_tooth) const {
  const Geometry& g = *geometry_;
  std::vector<double> out;
  if (g.spall_gear < 0) return out;
  const int index[2] = {pinion_tooth, wheel_tooth};
  if (index[g.spall_gear] != gear_.in.spall.tooth) return out;
  for (double x : {g.spall_lo, g.spall_hi})
    if (x > gear_.x_a && x < gear_.x_e) out.push_back(x);
  return out;
}

}  // namespace gear_dynamics
