#include "gear_dynamics/normal_stream.hpp"

#include <Random123/boxmuller.hpp>
#include <Random123/philox.h>

namespace gear_dynamics {

NormalStream::NormalStream(std::uint64_t seed, std::uint64_t realization)
    : key_{static_cast<std::uint32_t>(realization), static_cast<std::uint32_t>(seed)},
      seed_high_(static_cast<std::uint32_t>(seed >> 32)) {
  // The high realization bits share the counter word with the seed's high bits; 2^32
  // realizations per seed are far beyond any batch.
  seed_high_ ^= static_cast<std::uint32_t>(realization >> 32) * 0x9E3779B9u;
}

void NormalStream::pair(std::uint64_t pair_index, double& z0, double& z1) const {
  r123::Philox4x32 rng;
  const r123::Philox4x32::ctr_type ctr = {{static_cast<std::uint32_t>(pair_index),
                                           static_cast<std::uint32_t>(pair_index >> 32), seed_high_,
                                           0u}};
  const r123::Philox4x32::key_type key = {{key_[0], key_[1]}};
  const r123::Philox4x32::ctr_type bits = rng(ctr, key);
  const std::uint64_t u0 = (static_cast<std::uint64_t>(bits[1]) << 32) | bits[0];
  const std::uint64_t u1 = (static_cast<std::uint64_t>(bits[3]) << 32) | bits[2];
  const r123::double2 z = r123::boxmuller(u0, u1);
  z0 = z.x;
  z1 = z.y;
}

double NormalStream::at(std::uint64_t index) const {
  double z0, z1;
  pair(index / 2, z0, z1);
  return (index % 2 == 0) ? z0 : z1;
}

void NormalStream::fill(std::uint64_t first, double* out, std::size_t count) const {
  std::size_t k = 0;
  if (count > 0 && first % 2 == 1) out[k++] = at(first);
  for (; k + 1 < count; k += 2) pair((first + k) / 2, out[k], out[k + 1]);
  if (k < count) out[k] = at(first + k);
}

}  // namespace gear_dynamics
