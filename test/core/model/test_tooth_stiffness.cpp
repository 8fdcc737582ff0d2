// The potential-energy tooth pair (doc/model.md §3): each compliance term against an independent
// closed form (Tian's integrals, Yang & Lin's Hertz constant, Sainsot's formula by hand), the levels
// against the specification's cross-check and the ISO square wave, the overestimate without the
// fillet foundation, the quadrature's convergence, the crack and the spall.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/tooth_stiffness.hpp"

namespace gd = gear_dynamics;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Adaptive Simpson: an integrator independent of the model's Gauss-Legendre.
double simpson(const std::function<double(double)>& f, double a, double b, double tol, int depth = 40) {
  const auto step = [&](double lo, double hi, double flo, double fmid, double fhi, double whole, double eps, int d,
                        const auto& self) -> double {
    const double mid = 0.5 * (lo + hi), lm = 0.5 * (lo + mid), rm = 0.5 * (mid + hi);
    const double flm = f(lm), frm = f(rm);
    const double left = (mid - lo) / 6 * (flo + 4 * flm + fmid), right = (hi - mid) / 6 * (fmid + 4 * frm + fhi);
    if (d <= 0 || std::abs(left + right - whole) <= 15 * eps) return left + right + (left + right - whole) / 15;
    return self(lo, mid, flo, flm, fmid, left, eps / 2, d - 1, self) + self(mid, hi, fmid, frm, fhi, right, eps / 2, d - 1, self);
  };
  const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  return step(a, b, fa, fm, fb, (b - a) / 6 * (fa + 4 * fm + fb), tol, depth, step);
}

gd::GearInputs potential_energy() {
  gd::GearInputs in;
  in.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;
  return in;
}

// Mean single- and double-contact stiffness over the mesh cycle: pair 0 at x, pair 1 at x - pb.
std::pair<double, double> levels(const gd::GearPair& g, const gd::ToothPairStiffness& t) {
  const int n = 400;
  double single = 0.0, both = 0.0;
  for (int i = 0; i < n; ++i) {
    const double xs = g.x_b + (g.x_d - g.x_b) * (i + 0.5) / n, xd = g.x_d + (g.x_e - g.x_d) * (i + 0.5) / n;
    single += t.stiffness(xs, 0, 0);
    both += t.stiffness(xd, 0, 0) + t.stiffness(xd - g.base_pitch, 1, 1);
  }
  return {single / n, both / n};
}

}  // namespace

// The involute part of each tooth term is Tian's (2004) integral over his angle alpha in
// [-alpha1, alpha2]. With the dedendum chosen so that the root circle meets the base circle's
// involute start (no straight part below it), the model's terms must equal Tian's.
TEST(ToothStiffness, TermsMatchTiansIntegrals) {
  gd::GearInputs in = potential_energy();
  const double z = in.pinion_teeth, a0 = in.pressure_angle, m = 2 * in.pinion_pitch_radius / z;
  const double alpha2 = kPi / (2 * z) + std::tan(a0) - a0;
  const double rb = in.pinion_pitch_radius * std::cos(a0);
  in.dedendum_coefficient = (in.pinion_pitch_radius - rb * std::cos(alpha2)) / m;
  const gd::GearPair g = gd::derive(in);
  const gd::ToothPairStiffness t(g, {false, 64});
  const double E = in.youngs_modulus, L = in.face_width, nu = in.poisson_ratio;
  for (double x : {g.x_a, g.x_p, g.x_e}) {
    const double a1 = x / rb - alpha2;  // the load angle at roll length x
    const auto den = [&](double a) { return std::sin(a) + (alpha2 - a) * std::cos(a); };
    const double bend = simpson([&](double a) {
      const double n = 1 + std::cos(a1) * ((alpha2 - a) * std::sin(a) - std::cos(a));
      return 3 * n * n * (alpha2 - a) * std::cos(a) / (2 * E * L * std::pow(den(a), 3));
    }, -a1, alpha2, 1e-22);
    const double shear = simpson([&](double a) {
      return 1.2 * (1 + nu) * (alpha2 - a) * std::cos(a) * std::cos(a1) * std::cos(a1) / (E * L * den(a));
    }, -a1, alpha2, 1e-22);
    const double axial = simpson([&](double a) {
      return (alpha2 - a) * std::cos(a) * std::sin(a1) * std::sin(a1) / (2 * E * L * den(a));
    }, -a1, alpha2, 1e-22);
    const gd::PairCompliance c = t.compliance(x, 0, 0);
    EXPECT_NEAR(c.bending[0], bend, 1e-8 * bend) << "x = " << x;
    EXPECT_NEAR(c.shear[0], shear, 1e-8 * shear) << "x = " << x;
    EXPECT_NEAR(c.axial[0], axial, 1e-8 * axial + 1e-25) << "x = " << x;
    EXPECT_EQ(c.foundation[0], 0.0);
  }
}

// Hertz: 4 (1 - nu^2) / (pi E L), the same at every contact (Yang & Lin 1987).
TEST(ToothStiffness, HertzConstant) {
  const gd::GearPair g = gd::derive(potential_energy());
  const gd::ToothPairStiffness t(g);
  const double expected = 4 * (1 - 0.09) / (kPi * g.in.youngs_modulus * g.in.face_width);
  for (double x : {g.x_a, g.x_p, g.x_e}) EXPECT_NEAR(t.compliance(x, 0, 0).hertz, expected, 1e-14 * expected);
}

// Sainsot et al. (2004) at the pitch point of the pinion, evaluated here from the paper's formula
// and table: 1/k_f = cos^2(a_m)/(E L) [L* (u/S)^2 + M* (u/S) + P* (1 + Q* tan^2 a_m)].
TEST(ToothStiffness, FoundationBySainsotsFormula) {
  const gd::GearPair g = gd::derive(potential_energy());
  const double z = g.in.pinion_teeth, a0 = g.in.pressure_angle, rb = g.base_radius1, rf = g.root_radius1;
  const double alpha2 = kPi / (2 * z) + std::tan(a0) - a0;
  const double rho = 0.25 / (1 - std::sin(a0));  // cutter tip radius / m for c = 0.25
  const double theta_f = (kPi / 2 + 2 * std::tan(a0) * (1 - rho) + 2 * rho / std::cos(a0)) / z;
  const double h = rf / g.in.bore_radius1;
  const auto X = [&](double A, double B, double C, double D, double E, double F) {
    return A / (theta_f * theta_f) + B * h * h + C * h / theta_f + D / theta_f + E * h + F;
  };
  const double Ls = X(-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045);
  const double Ms = X(60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086);
  const double Ps = X(-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236);
  const double Qs = X(-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904);
  const double am = g.x_p / rb - alpha2;  // load angle at the pitch point
  const double yc = rb * ((am + alpha2) * std::sin(am) + std::cos(am));
  const double u = yc - rf, S = 2 * rf * theta_f;
  const double expected = std::cos(am) * std::cos(am) / (g.in.youngs_modulus * g.in.face_width) *
                          (Ls * (u / S) * (u / S) + Ms * (u / S) + Ps * (1 + Qs * std::tan(am) * std::tan(am)));
  EXPECT_NEAR(gd::ToothPairStiffness(g).compliance(g.x_p, 0, 0).foundation[0], expected, 1e-12 * expected);
}

// The levels: within 10 % of the model specification's potential-energy cross-check (1.21e8 and
// 2.07e8 N/m, its §3; doc/model.md §3) and of ISO's square wave; without the foundation term 2 to 3
// times stiffer (the known overestimate, about 2.4 in the specification).
TEST(ToothStiffness, LevelsAgainstTheCrossCheckAndIso) {
  const gd::GearPair g = gd::derive(potential_energy());
  const auto [single, both] = levels(g, gd::ToothPairStiffness(g));
  const auto [single_nf, both_nf] = levels(g, gd::ToothPairStiffness(g, {false, 64}));
  std::printf("potential energy: single contact %.4e N/m, double %.4e N/m (ratio %.3f); without the foundation "
              "%.4e, %.4e (x %.2f, x %.2f); ISO k1 %.4e, k2 %.4e\n",
              single, both, both / single, single_nf, both_nf, single_nf / single, both_nf / both, g.k1, g.k2);
  EXPECT_NEAR(single, 1.21e8, 0.1 * 1.21e8);
  EXPECT_NEAR(both, 2.07e8, 0.1 * 2.07e8);
  EXPECT_NEAR(single, g.k1, 0.1 * g.k1);
  EXPECT_NEAR(both, g.k2, 0.1 * g.k2);
  EXPECT_GT(single_nf / single, 2.0);
  EXPECT_LT(single_nf / single, 3.0);
}

// Gauss-Legendre converges: 16 nodes agree with 64 to 1e-6 at the contact's ends and the pitch point.
TEST(ToothStiffness, QuadratureConverges) {
  const gd::GearPair g = gd::derive(potential_energy());
  const gd::ToothPairStiffness coarse(g, {true, 16}), fine(g, {true, 64});
  for (double x : {g.x_a, g.x_p, g.x_e}) {
    const double k = fine.stiffness(x, 0, 0);
    EXPECT_NEAR(coarse.stiffness(x, 0, 0), k, 1e-6 * k) << "x = " << x;
  }
}

// A root crack lowers only the cracked tooth's pairs, more the deeper it is and the farther the
// contact from the root (the longer the lever over the cut sections).
TEST(ToothStiffness, CrackLowersTheCrackedToothMonotonically) {
  gd::GearInputs in = potential_energy();
  const gd::GearPair healthy = gd::derive(in);
  const gd::ToothPairStiffness h(healthy);
  double previous[3] = {1.0, 1.0, 1.0};
  for (double q : {0.25e-3, 0.5e-3, 1.0e-3, 1.5e-3}) {
    in.crack = {gd::FaultyGear::kPinion, 3, q, 0.7853981633974483};
    const gd::GearPair g = gd::derive(in);
    const gd::ToothPairStiffness t(g);
    const double xs[3] = {healthy.x_a, healthy.x_p, healthy.x_e};
    std::printf("crack %.2f mm:", q * 1e3);
    for (int k = 0; k < 3; ++k) {
      const double ratio = t.stiffness(xs[k], 3, 7) / h.stiffness(xs[k], 3, 7);
      std::printf(" %.4f", ratio);
      EXPECT_LT(ratio, previous[k]) << "q " << q << " x " << xs[k];
      previous[k] = ratio;
      EXPECT_EQ(t.stiffness(xs[k], 4, 7), h.stiffness(xs[k], 4, 7));  // another pinion tooth
    }
    std::printf(" of healthy at x_a, x_p, x_e\n");
    EXPECT_LT(previous[2], previous[0]);  // the tip load feels it most
  }
}

// A spall removes its width from the Hertzian contact while the contact crosses it, on its tooth only.
TEST(ToothStiffness, SpallNarrowsTheContact) {
  gd::GearInputs in = potential_energy();
  const gd::GearPair healthy = gd::derive(in);
  const double r = std::sqrt(healthy.base_radius1 * healthy.base_radius1 + healthy.x_p * healthy.x_p);
  in.spall = {gd::FaultyGear::kPinion, 2, 1.0e-3, 4.0e-3, r};
  const gd::GearPair g = gd::derive(in);
  const gd::ToothPairStiffness t(g), h(healthy);
  const auto edges = t.discontinuities(2, 0);
  ASSERT_EQ(edges.size(), 2u);
  EXPECT_NEAR(edges[0], healthy.x_p - 0.5e-3, 1e-12);
  EXPECT_NEAR(edges[1], healthy.x_p + 0.5e-3, 1e-12);
  EXPECT_TRUE(t.discontinuities(3, 0).empty());
  const double expected = 4 * (1 - 0.09) / (kPi * g.in.youngs_modulus * (g.in.face_width - 4.0e-3));
  EXPECT_NEAR(t.compliance(healthy.x_p, 2, 0).hertz, expected, 1e-14 * expected);
  EXPECT_EQ(t.stiffness(healthy.x_p + 0.6e-3, 2, 0), h.stiffness(healthy.x_p + 0.6e-3, 2, 0));
  EXPECT_EQ(t.stiffness(healthy.x_p, 3, 0), h.stiffness(healthy.x_p, 3, 0));
}

// Profile shifts: x1 = -x2 keeps the pressure angle and the centre distance; x1 + x2 != 0 meshes at
// the alpha_w of inv(alpha_w) = inv(alpha0) + 2 tan(alpha0) (x1 + x2)/(Z1 + Z2), found here by
// bisection, with the line of action (rb1 + rb2) tan(alpha_w); tip and root radii move by x m.
TEST(ToothStiffness, ProfileShiftGeometry) {
  gd::GearInputs in;
  const gd::GearPair plain = gd::derive(in);
  in.profile_shift1 = 0.3, in.profile_shift2 = -0.3;
  const gd::GearPair zero_sum = gd::derive(in);
  EXPECT_EQ(zero_sum.operating_pressure_angle, in.pressure_angle);
  EXPECT_NEAR(zero_sum.line_of_centres_length, plain.line_of_centres_length, 1e-15);
  EXPECT_NEAR(zero_sum.tip_radius1, plain.tip_radius1 + 0.3 * plain.module, 1e-15);
  EXPECT_NEAR(zero_sum.root_radius2, plain.root_radius2 - 0.3 * plain.module, 1e-15);
  in.profile_shift2 = 0.2;
  const gd::GearPair shifted = gd::derive(in);
  const double a0 = in.pressure_angle, inv0 = std::tan(a0) - a0;
  const double target = inv0 + 2 * std::tan(a0) * 0.5 / (in.pinion_teeth + in.gear_teeth);
  double lo = a0, hi = 0.6;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::tan(mid) - mid < target ? lo : hi) = mid;
  }
  EXPECT_NEAR(shifted.operating_pressure_angle, lo, 1e-14);
  EXPECT_NEAR(shifted.line_of_centres_length, (shifted.base_radius1 + shifted.base_radius2) * std::tan(lo), 1e-15);
  EXPECT_GT(shifted.contact_ratio, 1.0);
}
