// The sidebands of a gear whose teeth differ (spectrum.hpp). A file of its own: the code the
// compiler makes for welch_psd in spectrum.cpp changes its last bits with what else that file holds.
#include <cmath>

#include "gear_dynamics/maths/spectrum.hpp"

namespace gear_dynamics {

std::vector<Sideband> sidebands(const std::vector<double>& frequency, const std::vector<double>& density,
                                double mesh_frequency, double rotation_frequency, int harmonics, int orders) {
  std::vector<Sideband> out;
  if (frequency.size() < 5) return out;
  const double df = frequency[1] - frequency[0];
  const long n_bins = static_cast<long>(density.size());
  for (int n = 1; n <= harmonics; ++n) {
    for (int k = -orders; k <= orders; ++k) {
      const double target = n * mesh_frequency + k * rotation_frequency;
      const long j = std::lround(target / df);
      if (k == 0 || j < 2 || j + 2 >= n_bins) continue;
      long m = j;
      for (long i = j - 1; i <= j + 1; ++i)
        if (density[i] > density[m]) m = i;
      out.push_back({n, k, target, frequency[m], density[m], density[m] > density[m - 1] && density[m] > density[m + 1]});
    }
  }
  return out;
}

}  // namespace gear_dynamics
