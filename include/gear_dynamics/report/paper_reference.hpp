// The paper's published numbers (Tables 3 and 4, §3.2.3) that the report puts beside ours, in the
// paper's units. Data only; no ROS.
#pragma once

#include <vector>

namespace gear_dynamics {

struct PaperReference {
  double mu;
  double delta_T, delta_dot_T;  // Table 3 [mm], [mm/s]
  double p_delta, p_delta_dot;  // Table 4 [%] for [0.04, 0.055] mm and [-16, 16] mm/s
};
// One row per mu of the paper's sweep, ascending.
const std::vector<PaperReference>& paper_reference();
// The paper's row at mu (within 1e-9), or null.
const PaperReference* paper_at(double mu);

constexpr double kPaperExceedsS1 = 0.93;  // P(d > d_S1) at mu = 0.04 (93 of 100)
constexpr double kPaperMuExceeds = 0.04;

}  // namespace gear_dynamics
