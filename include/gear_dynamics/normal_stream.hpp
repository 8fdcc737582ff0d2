// One counter-based stream of standard normals per realization (MODEL.md §4): Random123's
// Philox4x32-10 keyed by (seed, realization), turned into normals by Random123's Box-Muller.
// Normal i of a stream depends only on (seed, realization, i), so a realization has the same path
// whatever runs beside it, in whatever order, on however many threads.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gear_dynamics {

class NormalStream {
 public:
  NormalStream(std::uint64_t seed, std::uint64_t realization);

  // Normal number `index` of the stream.
  double at(std::uint64_t index) const;
  // out[k] = at(first + k) for k < count.
  void fill(std::uint64_t first, double* out, std::size_t count) const;

 private:
  void pair(std::uint64_t pair_index, double& z0, double& z1) const;
  std::uint32_t key_[2];
  std::uint32_t seed_high_;
};

}  // namespace gear_dynamics
