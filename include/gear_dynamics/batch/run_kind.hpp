// The kinds of run in a batch (doc/model.md §4), as written in RunInfo.kind, RunSummary.kind and
// the manifest.
#pragma once

#include <optional>
#include <string>

namespace gear_dynamics {

enum class RunKind {
  S1,          // deterministic load, configured mesh phase
  Phase,       // deterministic load, phi0 = j phi_n / 64 (the phase ensemble)
  Stochastic,  // realization r of the load process
};
const char* to_string(RunKind kind);               // "S1", "phase", "stochastic"
std::optional<RunKind> run_kind_from(const std::string& text);

constexpr int kPhaseEnsembleSize = 64;  // members of the phase ensemble (doc/model.md §6)

}  // namespace gear_dynamics
