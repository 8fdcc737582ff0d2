#include "gear_dynamics/engine/instruction_set.hpp"

#include <cstdlib>
#include <stdexcept>

#include "dispatch.hpp"

namespace gear_dynamics {

namespace {

constexpr InstructionSet kAll[] = {InstructionSet::baseline, InstructionSet::avx2, InstructionSet::avx512};

struct Choice {
  InstructionSet isa;
  bool forced;
};

Choice choose() {
  const char* forced = std::getenv(kInstructionSetVariable);
  if (forced == nullptr || *forced == '\0') return {supported_instruction_sets().back(), false};
  const InstructionSet isa = parse_instruction_set(forced, kInstructionSetVariable);
  if (!cpu_supports(isa)) {
    std::string runs;
    for (InstructionSet s : supported_instruction_sets()) runs += std::string(runs.empty() ? "" : ", ") + to_string(s);
    throw std::runtime_error(std::string(kInstructionSetVariable) + "=" + forced + ": this CPU does not run " + forced +
                             " code; it runs " + runs);
  }
  return {isa, true};
}

// Chosen once: the first call decides for the process (a refused GEAR_DYNAMICS_ISA throws at every call).
const Choice& choice() {
  static const Choice c = choose();
  return c;
}

}  // namespace

const char* to_string(InstructionSet isa) {
  switch (isa) {
    case InstructionSet::baseline: return "baseline";
    case InstructionSet::avx2: return "avx2";
    case InstructionSet::avx512: return "avx512";
  }
  return "unknown";
}

InstructionSet parse_instruction_set(const std::string& value, const std::string& source) {
  for (InstructionSet isa : kAll)
    if (value == to_string(isa)) return isa;
  throw std::invalid_argument(source + " = '" + value + "' is not an instruction set; allowed: baseline, avx2, avx512");
}

bool cpu_supports(InstructionSet isa) {
  __builtin_cpu_init();  // idempotent; needed before main (static initializers)
  switch (isa) {
    case InstructionSet::baseline: return true;
    // The levels' full feature lists (and the operating system's support of the wider registers),
    // what -march=x86-64-v3 / -v4 compile for.
    case InstructionSet::avx2: return __builtin_cpu_supports("x86-64-v3");
    case InstructionSet::avx512: return __builtin_cpu_supports("x86-64-v4");
  }
  return false;
}

std::vector<InstructionSet> supported_instruction_sets() {
  std::vector<InstructionSet> out;
  for (InstructionSet isa : kAll)
    if (cpu_supports(isa)) out.push_back(isa);
  return out;
}

InstructionSet active_instruction_set() { return choice().isa; }

std::string instruction_set_description() {
  const Choice& c = choice();
  return std::string("instruction set: ") + to_string(c.isa) +
         (c.forced ? std::string(" (forced by ") + kInstructionSetVariable + ")" : " (best this CPU runs)");
}

namespace dispatch {

const Kernels& kernels_of(InstructionSet isa) {
  switch (isa) {
    case InstructionSet::avx512: return *gd_isa_kernels_avx512();
    case InstructionSet::avx2: return *gd_isa_kernels_avx2();
    case InstructionSet::baseline: break;
  }
  return *gd_isa_kernels_baseline();
}

const Kernels& kernels() {
  static const Kernels& table = kernels_of(active_instruction_set());
  return table;
}

}  // namespace dispatch

}  // namespace gear_dynamics
