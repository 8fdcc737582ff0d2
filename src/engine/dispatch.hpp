// The engine's hot paths compiled once per instruction set (CMakeLists.txt's GD_DISPATCHED_SOURCES)
// and chosen at run time (instruction_set.cpp). Each variant is partially linked on its own and keeps
// one global symbol, its table below: every inline function and template it instantiates (Eigen's,
// std's, Boost's) stays its own copy, so no code of one instruction set is ever called from another.
// Every variant computes the same numbers bit for bit (explicit fused multiply-adds, integer Philox,
// -ffp-contract=off), so the choice changes speed only.
#pragma once

#include <cstddef>
#include <cstdint>

#include "gear_dynamics/engine/instruction_set.hpp"
#include "gear_dynamics/model/mesh_schedule.hpp"

namespace gear_dynamics {
class BearingsModel;
}

namespace gear_dynamics::dispatch {

// Grid step n of an Ensemble's padded lanes (Ensemble::step's arrays, lanes a multiple of the
// packet), with the step's normals z. The step's plan is made inside the variant (inlined there).
struct EnsembleStep {
  const MeshSchedule* mesh;
  std::int64_t n;
  double h, sqrt_h, backlash, alpha, q3;
  double *delta, *velocity, *load;
  const double *mu, *sigma, *drift, *z;
  std::ptrdiff_t lanes;
};

// Grid step n of a Realization's one lane (engine/realization.hpp), with its normal z.
struct RealizationStep {
  const MeshSchedule* mesh;
  std::int64_t n;
  double h, sqrt_h, backlash, alpha, q3, mu, drift, sigma, z;
  double *delta, *velocity, *load;
};

// Grid step n of an Ensemble's padded lanes of the bearings model (Ensemble::step_bearings): the
// state component-major (component k of lane i at state[k * stride + i]), delta and velocity the
// mesh deflection and its rate written after the step.
struct BearingsEnsembleStep {
  const BearingsModel* model;
  const GearPair* gear;
  const MeshSchedule* mesh;
  std::int64_t n;
  double h, sqrt_h;
  double* state;
  std::ptrdiff_t stride;
  double *delta, *velocity, *load;
  const double *mu, *sigma, *drift, *z;
  std::ptrdiff_t lanes;
};
// A NormalStream's key and counter word, and a NormalLanes' per lane.
struct StreamKey {
  std::uint32_t key0, key1, seed_high;
};
struct LaneKeys {
  const std::uint32_t *key0, *key1, *seed_high;
  const std::uint64_t (*round_keys)[2][8];  // NormalLanes::round_keys_
};

struct Kernels {
  InstructionSet isa;
  // Steps the lanes; false when the state is no longer finite (the caller finds the lane).
  bool (*ensemble_step)(const EnsembleStep&);
  void (*realization_step)(const RealizationStep&);
  // The bearings model's lanes; false when the state is no longer finite.
  bool (*bearings_ensemble_step)(const BearingsEnsembleStep&);
  void (*philox)(const StreamKey&, std::uint64_t first_pair, std::uint64_t* w0, std::uint64_t* w1);
  void (*normal_block)(const StreamKey&, std::uint64_t first_pair, double* out);
  void (*normal_lanes_block)(const LaneKeys&, std::uint64_t first_pair, double* out, std::ptrdiff_t stride);
};

// The variant chosen once per process (GEAR_DYNAMICS_ISA or the best the CPU runs).
const Kernels& kernels();
// The variant of `isa`, whether or not this CPU runs it (the tests compare the variants).
const Kernels& kernels_of(InstructionSet isa);

}  // namespace gear_dynamics::dispatch

// The variants' tables, one per instruction set the build compiles (C names: the one symbol each
// variant exports).
extern "C" const gear_dynamics::dispatch::Kernels* gd_isa_kernels_baseline();
extern "C" const gear_dynamics::dispatch::Kernels* gd_isa_kernels_avx2();
extern "C" const gear_dynamics::dispatch::Kernels* gd_isa_kernels_avx512();
