// The bearings model's SIMD ensemble kernel (src/engine/dispatched/bearings_step.cpp) in every
// instruction-set variant this CPU runs, against bearings_step (the located segment of the model
// seam, one lane at a time: an independent path, the crossing search on every segment): the same
// state bit for bit, on every lane, through impacts, at the paper's load and at 1 kN with reversing
// friction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "../../../src/engine/dispatch.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/bearings.hpp"
#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"

namespace gd = gear_dynamics;
namespace dispatch = gear_dynamics::dispatch;
using M = gd::BearingsModel;

TEST(BearingsStep, EveryVariantsLanesAreBearingsStep) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  const gd::ModelConfig c =
      gd::parse_config(gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
  constexpr int kLanes = 40, kSteps = 4000;  // 16 + 16 + 8 lanes: both packet widths; 10 ms, past the first impacts
  for (const bool heavy : {false, true}) {
    gd::GearInputs in = c.gear;
    in.model = gd::GearModel::kBearings;
    if (heavy) in.friction_direction = gd::FrictionDirection::kReversing;
    const gd::GearPair gear = gd::derive(in);
    const double h = c.run.time_step, b = gear.in.backlash;
    const gd::MeshSchedule mesh(gear, h);
    const M model(gear);
    // Each lane its own stream, friction (0 in some) and load; starts from rest and across the backlash.
    std::vector<double> z(static_cast<std::size_t>(kSteps) * kLanes);
    for (int l = 0; l < kLanes; ++l) {
      std::vector<double> normals(kSteps + 1);
      gd::NormalStream(c.seed, static_cast<std::uint64_t>(l)).fill(0, normals.data(), normals.size());
      for (int n = 0; n < kSteps; ++n) z[static_cast<std::size_t>(n) * kLanes + l] = normals[n + 1];
    }
    std::vector<double> state0(M::kStates * kLanes, 0.0), load0(kLanes), mu(kLanes), sigma(kLanes), drift(kLanes);
    for (int l = 0; l < kLanes; ++l) {
      state0[M::kDelta * kLanes + l] = (l % 7 - 3) * 0.6 * b;
      state0[M::kDeltaDot * kLanes + l] = (l % 5 - 2) * 0.01;
      load0[l] = (heavy ? 2.0e4 : 20.0) + l;
      mu[l] = 0.02 * (l % 3);
      sigma[l] = (heavy ? 100.0 : 0.5) * (l % 4);
      drift[l] = l % 3 == 0 ? 10.0 : 0.0;
    }
    // The reference: bearings_step lane by lane, with BearingsRealization's load step.
    std::vector<M::State> ref(kLanes);
    std::vector<double> ref_load = load0;
    for (int l = 0; l < kLanes; ++l)
      for (int k = 0; k < M::kStates; ++k) ref[l][k] = state0[k * kLanes + l];
    std::int64_t crossings = 0;
    for (int n = 0; n < kSteps; ++n) {
      for (int l = 0; l < kLanes; ++l) {
        const double load1 = std::fma(sigma[l] * std::sqrt(h), z[static_cast<std::size_t>(n) * kLanes + l],
                                      std::fma(drift[l], h, ref_load[l]));
        crossings += gd::bearings_step(model, gear, mesh, h, mu[l], n, ref_load[l], load1, ref[l]);
        ref_load[l] = load1;
      }
    }
    // Impacts in enough lanes for the located fallback to be exercised.
    EXPECT_GT(crossings, kLanes) << (heavy ? "1 kN" : "paper's load");
    for (gd::InstructionSet isa : gd::supported_instruction_sets()) {
      std::vector<double> state = state0, load = load0, delta(kLanes), velocity(kLanes);
      for (int n = 0; n < kSteps; ++n) {
        const dispatch::BearingsEnsembleStep step{&model,        &gear,         &mesh,          n,
                                                  h,             std::sqrt(h),  state.data(),   kLanes,
                                                  delta.data(),  velocity.data(), load.data(),  mu.data(),
                                                  sigma.data(),  drift.data(),  &z[static_cast<std::size_t>(n) * kLanes],
                                                  kLanes};
        ASSERT_TRUE(dispatch::kernels_of(isa).bearings_ensemble_step(step)) << gd::to_string(isa) << " step " << n;
      }
      for (int l = 0; l < kLanes; ++l) {
        M::State got;
        for (int k = 0; k < M::kStates; ++k) got[k] = state[k * kLanes + l];
        EXPECT_EQ(std::memcmp(got.data(), ref[l].data(), sizeof(double) * M::kStates), 0)
            << gd::to_string(isa) << " lane " << l << (heavy ? " (1 kN)" : "");
        EXPECT_EQ(std::memcmp(&load[l], &ref_load[l], sizeof(double)), 0) << gd::to_string(isa) << " lane " << l;
        const double dm = model.deflection(ref[l]), rate = model.deflection_rate(ref[l]);
        EXPECT_EQ(std::memcmp(&delta[l], &dm, sizeof dm), 0) << gd::to_string(isa) << " lane " << l;
        EXPECT_EQ(std::memcmp(&velocity[l], &rate, sizeof rate), 0) << gd::to_string(isa) << " lane " << l;
      }
      // The run moved every lane (a step that did nothing would agree trivially).
      for (int l = 0; l < kLanes; ++l) EXPECT_NE(state[M::kPinionY * kLanes + l], 0.0) << "lane " << l;
    }
  }
}
