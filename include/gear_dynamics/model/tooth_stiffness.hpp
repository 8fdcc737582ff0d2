// Stiffness of one tooth pair from the tooth geometry by the potential-energy method (doc/model.md
// §3): bending, shear and axial compression of each tooth (Yang & Lin 1987, Tian 2004), the
// Hertzian contact of the pair, and the fillet foundation of each gear (Sainsot et al. 2004), all in
// series. A root crack (Chaari et al. 2009) lowers the cracked tooth's section; a spall takes its
// area out of the contact. SI units; no ROS.
#pragma once

#include <memory>
#include <vector>

#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_dynamics {

// The compliance terms [m/N] of a tooth pair at one contact point; index 0 the pinion, 1 the wheel.
struct PairCompliance {
  double hertz = 0.0;
  double bending[2] = {0.0, 0.0};
  double shear[2] = {0.0, 0.0};
  double axial[2] = {0.0, 0.0};
  double foundation[2] = {0.0, 0.0};
  double total() const {
    return hertz + bending[0] + shear[0] + axial[0] + foundation[0] + bending[1] + shear[1] + axial[1] +
           foundation[1];
  }
};

struct PotentialEnergyOptions {
  bool fillet_foundation = true;  // false: the known overestimate without Sainsot's term
  int quadrature_points = 64;     // Gauss-Legendre nodes per integral
};

class ToothPairStiffness {
 public:
  // Uses the geometry of `gear` (module, teeth, pressure angle, addendum, dedendum, profile shifts,
  // bores, face width, E, nu) and its crack and spall.
  explicit ToothPairStiffness(const GearPair& gear, PotentialEnergyOptions options = {});

  // The pair of pinion tooth i and wheel tooth j in contact at x, the contact's distance from C1
  // along the line of action [m], x in [x_a, x_e].
  PairCompliance compliance(double x, int pinion_tooth, int wheel_tooth) const;
  double stiffness(double x, int pinion_tooth, int wheel_tooth) const {
    return 1.0 / compliance(x, pinion_tooth, wheel_tooth).total();
  }
  // The x in (x_a, x_e) where that pair's stiffness jumps (a spall's edges), increasing.
  std::vector<double> discontinuities(int pinion_tooth, int wheel_tooth) const;

 private:
  struct Geometry;  // both teeth's profiles, the crack's and the spall's extent
  GearPair gear_;
  PotentialEnergyOptions options_;
  std::vector<double> nodes_, weights_;  // Gauss-Legendre on [-1, 1]
  std::shared_ptr<const Geometry> geometry_;
};

}  // namespace gear_dynamics
