// The batch analysis as this package's BatchReport message (SI units, REP 103).
#pragma once

#include <string>

#include "gear_dynamics/BatchReport.h"
#include "gear_dynamics/report/report.hpp"

namespace gear_dynamics {

BatchReport make_report_message(const BatchInputs& inputs, const BatchAnalysis& analysis,
                                const std::string& report_folder);

}  // namespace gear_dynamics
