// Included first by every dispatched source (src/engine/dispatched/): GD_ISA, set by CMakeLists.txt
// per compilation (baseline, avx2, avx512), names the variant's namespace, so that even before the
// partial link hides them the variants' own functions never share a name.
#pragma once

#include "../dispatch.hpp"

#ifndef GD_ISA
#error "a dispatched source is compiled once per instruction set, with -DGD_ISA=<name> (CMakeLists.txt)"
#endif
#define GD_ISA_JOIN2(a, b) a##b
#define GD_ISA_JOIN(a, b) GD_ISA_JOIN2(a, b)
#define GD_ISA_NAMESPACE GD_ISA_JOIN(isa_, GD_ISA)

namespace gear_dynamics::GD_ISA_NAMESPACE {

bool ensemble_step(const dispatch::EnsembleStep& step);
void realization_step(const dispatch::RealizationStep& step);
bool bearings_ensemble_step(const dispatch::BearingsEnsembleStep& step);
void philox(const dispatch::StreamKey& key, std::uint64_t first_pair, std::uint64_t* w0, std::uint64_t* w1);
void normal_block(const dispatch::StreamKey& key, std::uint64_t first_pair, double* out);
void normal_lanes_block(const dispatch::LaneKeys& keys, std::uint64_t first_pair, double* out, std::ptrdiff_t stride);

}  // namespace gear_dynamics::GD_ISA_NAMESPACE
