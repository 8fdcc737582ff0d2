// The variant's table: the only symbol its partial link leaves global (CMakeLists.txt).
#include "variant.hpp"

namespace gear_dynamics::GD_ISA_NAMESPACE {
namespace {

constexpr dispatch::Kernels kKernels{InstructionSet::GD_ISA, ensemble_step, realization_step, bearings_ensemble_step, philox, normal_block, normal_lanes_block};

}  // namespace
}  // namespace gear_dynamics::GD_ISA_NAMESPACE

extern "C" const gear_dynamics::dispatch::Kernels* GD_ISA_JOIN(gd_isa_kernels_, GD_ISA)() {
  return &gear_dynamics::GD_ISA_NAMESPACE::kKernels;
}
