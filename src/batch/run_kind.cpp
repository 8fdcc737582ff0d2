#include "gear_dynamics/batch/run_kind.hpp"

namespace gear_dynamics {

const char* to_string(RunKind kind) {
  switch (kind) {
    case RunKind::S1: return "S1";
    case RunKind::Phase: return "phase";
    case RunKind::Stochastic: return "stochastic";
  }
  return "?";
}

std::optional<RunKind> run_kind_from(const std::string& text) {
  for (RunKind k : {RunKind::S1, RunKind::Phase, RunKind::Stochastic})
    if (text == to_string(k)) return k;
  return std::nullopt;
}

}  // namespace gear_dynamics
