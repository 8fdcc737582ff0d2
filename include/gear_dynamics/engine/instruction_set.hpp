// The instruction set the engine's hot paths (the ensemble's RK4 step, the normal generator) run
// with. The build compiles them for each x86-64 level and picks one per process: the best this CPU
// runs, or the one the environment variable GEAR_DYNAMICS_ISA names. All give the same numbers bit
// for bit (doc/architecture.md, "Instruction sets"); the choice is recorded in a run's logs and
// metadata.
#pragma once

#include <string>
#include <vector>

namespace gear_dynamics {

enum class InstructionSet {
  baseline,  // x86-64 (SSE2): every x86-64 CPU
  avx2,      // x86-64-v3: AVX2, FMA
  avx512,    // x86-64-v4: AVX-512 F, DQ, VL, BW, CD
};

// The environment variable that forces a choice.
constexpr const char* kInstructionSetVariable = "GEAR_DYNAMICS_ISA";

const char* to_string(InstructionSet isa);
// Parses "baseline", "avx2" or "avx512"; throws std::invalid_argument naming `source`, the value
// and the allowed values otherwise.
InstructionSet parse_instruction_set(const std::string& value, const std::string& source);
// Whether this CPU (and its operating system) runs code compiled for isa.
bool cpu_supports(InstructionSet isa);
// The instruction sets this CPU runs, lowest first.
std::vector<InstructionSet> supported_instruction_sets();
// The one the hot paths use in this process, chosen at the first call (thread-safe): the value of
// GEAR_DYNAMICS_ISA if set (std::invalid_argument if not a name above, std::runtime_error if this
// CPU lacks it), else the best the CPU supports.
InstructionSet active_instruction_set();
// One line for a program's start-up log: "instruction set: avx512 (best this CPU runs)" or
// "(forced by GEAR_DYNAMICS_ISA)".
std::string instruction_set_description();

}  // namespace gear_dynamics
