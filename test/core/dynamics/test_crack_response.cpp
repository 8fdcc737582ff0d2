// The response of a gear with a cracked tooth (doc/model.md §4): the sidebands of its mesh force
// spectrum, from the engine's run and the maths layer's Welch PSD.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/maths/spectrum.hpp"
#include "gear_dynamics/model/gear_pair.hpp"

namespace gd = gear_dynamics;

// A cracked pinion tooth modulates the mesh once per pinion revolution: the mesh force of a
// deterministic run (100 times the paper's load, teeth in contact) has lines at f_m +- k f_1,
// k = 1, 2, around the first two mesh harmonics, each within one bin; the healthy gear's spectrum
// has none there (the cracked run's density is over 100 times the healthy one's at those bins).
// Segments of 4 pinion revolutions put f_1 4 bins apart, clear of the Hann leakage of a harmonic.
TEST(CrackResponse, SidebandsAtThePinionRotation) {
  const auto run = [](bool cracked) {
    gd::GearInputs in;
    in.mesh_stiffness = gd::MeshStiffnessModel::kPotentialEnergy;
    if (cracked) in.crack = {gd::FaultyGear::kPinion, 0, 1.0e-3, 0.7853981633974483};
    const gd::GearPair g = gd::derive(in);
    const double h = 2.5e-6, load = 2000.0;
    const gd::LaneSpec lane{0.04, 0.0, 0.0, load, 0.0, 0, false};
    gd::Ensemble e(g, h, {g.in.backlash + load / (g.q3 * 1.7e8), 0.0}, {lane}, 1);
    std::vector<double> force;
    for (int n = 0; n <= 400000; ++n) {
      if (n >= 160000 && n % 4 == 0)
        force.push_back(gd::mesh_force(g, e.mesh().stiffness(e.time()), e.delta()[0], e.velocity()[0],
                                       e.mesh().transmission_error(e.time()), e.mesh().transmission_error_rate(e.time())));
      if (n < 400000) e.step();
    }
    const double fm = g.mesh_frequency(), fs = 1.0 / (4 * h);
    // 80 mesh periods = 4 pinion revolutions: harmonics and sidebands on bin centres.
    const gd::Psd p = gd::welch_psd(force, fs, {static_cast<std::size_t>(std::lround(80 / fm * fs)), 0.5});
    return std::make_pair(p, gd::sidebands(p.frequency, p.density, fm, fm / g.in.pinion_teeth, 2, 2));
  };
  const auto [cracked_psd, cracked] = run(true);
  const auto [healthy_psd, healthy] = run(false);
  ASSERT_EQ(cracked.size(), 8u);
  for (std::size_t i = 0; i < cracked.size(); ++i) {
    EXPECT_TRUE(cracked[i].line) << "n " << cracked[i].harmonic << " k " << cracked[i].order << " at "
                                 << cracked[i].frequency << " Hz";
    EXPECT_LE(std::abs(cracked[i].bin_frequency - cracked[i].frequency), cracked_psd.resolution);
    EXPECT_GT(cracked[i].density, 100.0 * healthy[i].density) << cracked[i].frequency << " Hz";
  }
}
