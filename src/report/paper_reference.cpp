#include "gear_dynamics/report/paper_reference.hpp"

#include <cmath>

namespace gear_dynamics {

const std::vector<PaperReference>& paper_reference() {
  static const std::vector<PaperReference> table = {
      {0.00, 0.0515, -2.167, 91, 80}, {0.01, 0.0431, -10.59, 89, 79}, {0.02, 0.0511, 7.079, 85, 90},
      {0.03, 0.0515, 6.854, 76, 90},  {0.04, 0.0508, -9.459, 87, 89}, {0.05, 0.0453, -28.38, 85, 87}};
  return table;
}

const PaperReference* paper_at(double mu) {
  for (const PaperReference& p : paper_reference())
    if (std::abs(p.mu - mu) < 1e-9) return &p;
  return nullptr;
}

}  // namespace gear_dynamics
