#include "gear_dynamics/batch/run_record.hpp"

#include <algorithm>
#include <cmath>

namespace gear_dynamics {

bool same_value(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(1.0, std::abs(b)); }

}  // namespace gear_dynamics
