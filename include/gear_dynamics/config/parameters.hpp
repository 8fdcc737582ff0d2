// Every configuration section's declaration in one list, for the docs (gear_run
// --print-parameters) and the tests (generated bad input, docs in step with the code).
#pragma once

#include <string>
#include <vector>

#include "gear_dynamics/config/section.hpp"

namespace gear_dynamics {

// gear_pair, load, run, monte_carlo, simulator, analysis and aggregator (gear_aggregator's own keys).
std::vector<SectionSpec> parameter_sections();

// The section's Markdown table: key, type, unit, default, allowed values, meaning. The docs carry
// it between "<!-- parameters: NAME -->" and "<!-- /parameters -->" (test_parameters_doc).
std::string parameter_table(const SectionSpec& section);

}  // namespace gear_dynamics
