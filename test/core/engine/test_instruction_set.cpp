// The instruction-set variants of the engine's hot paths (src/engine/dispatched/) against each other:
// every variant this CPU runs gives the baseline variant's numbers bit for bit (the Philox words,
// the normals of one stream and of 8 lanes side by side, and 20 000 ensemble steps of 56 lanes, which
// take the 4-, 2- and 1-packet paths and the located backlash crossings of the start-up rattle), and
// the choice's names and refusals. The processes forced to each variant and the builds under other
// CPUs are test/isa/isa_check.py's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "../../../src/engine/dispatch.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/engine/ensemble.hpp"
#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/engine/normal_stream.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gd = gear_dynamics;
namespace dispatch = gear_dynamics::dispatch;

namespace {

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

}  // namespace

TEST(InstructionSet, NamesParseAndRefuse) {
  for (gd::InstructionSet isa : {gd::InstructionSet::baseline, gd::InstructionSet::avx2, gd::InstructionSet::avx512})
    EXPECT_EQ(gd::parse_instruction_set(gd::to_string(isa), "X"), isa);
  try {
    gd::parse_instruction_set("avx3", "GEAR_DYNAMICS_ISA");
    FAIL() << "avx3 accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    for (const char* part : {"GEAR_DYNAMICS_ISA", "avx3", "baseline, avx2, avx512"})
      EXPECT_NE(what.find(part), std::string::npos) << what;
  }
  const auto supported = gd::supported_instruction_sets();
  ASSERT_FALSE(supported.empty());
  EXPECT_EQ(supported.front(), gd::InstructionSet::baseline);  // every x86-64 runs it
  EXPECT_TRUE(gd::cpu_supports(gd::active_instruction_set()));
  // Each table is the variant it names.
  for (gd::InstructionSet isa : supported) EXPECT_EQ(dispatch::kernels_of(isa).isa, isa);
  std::printf("this CPU runs:");
  for (gd::InstructionSet isa : supported) std::printf(" %s", gd::to_string(isa));
  std::printf("; active %s\n", gd::to_string(gd::active_instruction_set()));
}

TEST(InstructionSet, NormalGeneratorVariantsAgree) {
  const dispatch::StreamKey key{7u, 20180529u, 0u};  // NormalStream(20180529, 7)'s key and counter word
  const std::uint64_t lane_realizations[8] = {0, 1, 2, 3, 100, 1000, 4294967295ull, 5};
  // The raw keys of NormalLanes as its constructor derives them (kept private there).
  std::uint32_t k0[8], k1[8], hi[8];
  alignas(64) std::uint64_t round_keys[10][2][8];
  for (int l = 0; l < 8; ++l) {
    k0[l] = static_cast<std::uint32_t>(lane_realizations[l]);
    k1[l] = 20180529u;
    hi[l] = 0u;
    for (int r = 0; r < 10; ++r) {
      round_keys[r][0][l] = k0[l] + static_cast<std::uint32_t>(r) * 0x9E3779B9u;
      round_keys[r][1][l] = k1[l] + static_cast<std::uint32_t>(r) * 0xBB67AE85u;
    }
  }
  const dispatch::LaneKeys keys{k0, k1, hi, round_keys};
  constexpr int kPairs = gd::NormalStream::kBlockPairs, kBlocks = 400;  // 25 600 normals per lane
  const auto run = [&](const dispatch::Kernels& k) {
    std::vector<std::uint64_t> words(2 * kPairs * kBlocks);
    std::vector<double> one(2 * kPairs * kBlocks), eight(16 * kPairs * kBlocks);
    for (int b = 0; b < kBlocks; ++b) {
      const std::uint64_t first = static_cast<std::uint64_t>(b) * kPairs;
      k.philox(key, first, &words[2 * kPairs * b], &words[2 * kPairs * b + kPairs]);
      k.normal_block(key, first, &one[2 * kPairs * b]);
      k.normal_lanes_block(keys, first, &eight[16 * kPairs * b], 8);
    }
    return std::make_tuple(words, one, eight);
  };
  const auto reference = run(dispatch::kernels_of(gd::InstructionSet::baseline));
  for (gd::InstructionSet isa : gd::supported_instruction_sets()) {
    const auto got = run(dispatch::kernels_of(isa));
    EXPECT_TRUE(same_bytes(std::get<0>(got), std::get<0>(reference))) << gd::to_string(isa) << ": Philox words";
    EXPECT_TRUE(same_bytes(std::get<1>(got), std::get<1>(reference))) << gd::to_string(isa) << ": one stream";
    EXPECT_TRUE(same_bytes(std::get<2>(got), std::get<2>(reference))) << gd::to_string(isa) << ": 8 lanes";
  }
  // And the process's own generator (its chosen variant) is the same stream.
  gd::NormalStream stream(20180529, 7);
  std::vector<double> filled(2 * kPairs * 4);
  stream.fill(0, filled.data(), filled.size());
  for (std::size_t i = 0; i < filled.size(); ++i)
    ASSERT_EQ(std::memcmp(&filled[i], &std::get<1>(reference)[i], sizeof(double)), 0) << "normal " << i;
}

TEST(InstructionSet, EnsembleStepVariantsAgree) {
  const std::string dir = GEAR_DYNAMICS_CONFIG_DIR;
  const gd::ModelConfig c =
      gd::parse_config(gd::read_yaml_files({dir + "/gear_pair.yaml", dir + "/load.yaml", dir + "/run.yaml"}));
  const gd::GearPair gear = derive(c.gear);
  const double h = c.run.time_step;
  const gd::MeshSchedule mesh(gear, h);
  constexpr int kLanes = 56, kSteps = 20000;  // 32 + 16 + 8 lanes: every packet path
  // Each lane its own stream, mu and start: from rest, and from deflections across the backlash.
  std::vector<double> z(static_cast<std::size_t>(kSteps) * kLanes);
  for (int l = 0; l < kLanes; ++l) {
    std::vector<double> normals(kSteps + 1);
    gd::NormalStream(c.seed, static_cast<std::uint64_t>(l)).fill(0, normals.data(), normals.size());
    for (int n = 0; n < kSteps; ++n) z[static_cast<std::size_t>(n) * kLanes + l] = normals[n + 1];
  }
  struct Lanes {
    std::vector<double> d, v, load, mu, sigma, drift;
  };
  Lanes start{std::vector<double>(kLanes), std::vector<double>(kLanes), std::vector<double>(kLanes),
              std::vector<double>(kLanes), std::vector<double>(kLanes), std::vector<double>(kLanes)};
  const double b = gear.in.backlash;
  for (int l = 0; l < kLanes; ++l) {
    start.d[l] = (l % 7 - 3) * 0.6 * b;
    start.v[l] = (l % 5 - 2) * 0.01;
    start.load[l] = 20.0 + l;
    start.mu[l] = 0.01 * (l % 6);
    start.sigma[l] = 0.5 * (l % 4);
    start.drift[l] = l % 3 == 0 ? 10.0 : 0.0;
  }
  const auto run = [&](const dispatch::Kernels& k) {
    Lanes s = start;
    for (int n = 0; n < kSteps; ++n) {
      const dispatch::EnsembleStep step{&mesh, n, h, std::sqrt(h), b, gear.damping_coefficient, gear.q3,
                                        s.d.data(), s.v.data(), s.load.data(), s.mu.data(), s.sigma.data(),
                                        s.drift.data(), &z[static_cast<std::size_t>(n) * kLanes], kLanes};
      if (!k.ensemble_step(step)) ADD_FAILURE() << "not finite at step " << n;
    }
    return s;
  };
  const Lanes reference = run(dispatch::kernels_of(gd::InstructionSet::baseline));
  for (gd::InstructionSet isa : gd::supported_instruction_sets()) {
    const Lanes got = run(dispatch::kernels_of(isa));
    EXPECT_TRUE(same_bytes(got.d, reference.d)) << gd::to_string(isa) << ": delta";
    EXPECT_TRUE(same_bytes(got.v, reference.v)) << gd::to_string(isa) << ": delta_dot";
    EXPECT_TRUE(same_bytes(got.load, reference.load)) << gd::to_string(isa) << ": load";
  }
  // The run moved every lane (a step that did nothing would agree trivially).
  for (int l = 0; l < kLanes; ++l) EXPECT_NE(reference.d[l], start.d[l]) << "lane " << l;
}
