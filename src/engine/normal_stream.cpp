#include "gear_dynamics/engine/normal_stream.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

// The generator's SIMD parts run in the instruction-set variant chosen for the process
// (src/engine/dispatched/normal_kernels.cpp); Philox's key schedule constants come from here.
#include "dispatch.hpp"
#include "normal/common.hpp"

namespace gear_dynamics {

using normals::kPhiloxW0;
using normals::kPhiloxW1;

NormalStream::NormalStream(std::uint64_t seed, std::uint64_t realization)
    : key_{static_cast<std::uint32_t>(realization), static_cast<std::uint32_t>(seed)},
      seed_high_(static_cast<std::uint32_t>(seed >> 32)) {
  // The key holds 32 bits of the realization: a higher index would share its stream with another
  // (seed, realization) pair.
  if (realization >> 32)
    throw std::invalid_argument("NormalStream: realization " + std::to_string(realization) +
                                " is out of range; allowed [0, 4294967295] (32 bits of the stream key)");
}

void NormalStream::philox(std::uint64_t first_pair, std::uint64_t* w0, std::uint64_t* w1) const {
  dispatch::kernels().philox({key_[0], key_[1], seed_high_}, first_pair, w0, w1);
}

void NormalStream::block(std::uint64_t first_pair, double* out) const {
  dispatch::kernels().normal_block({key_[0], key_[1], seed_high_}, first_pair, out);
}

NormalLanes::NormalLanes(std::uint64_t seed, const std::uint64_t (&realizations)[kLanes]) {
  for (int l = 0; l < kLanes; ++l) {
    const NormalStream stream(seed, realizations[l]);
    key0_[l] = stream.key_[0];
    key1_[l] = stream.key_[1];
    seed_high_[l] = stream.seed_high_;
    for (int round = 0; round < 10; ++round) {  // uint32_t arithmetic: wraps as Philox's does
      round_keys_[round][0][l] = key0_[l] + static_cast<std::uint32_t>(round) * kPhiloxW0;
      round_keys_[round][1][l] = key1_[l] + static_cast<std::uint32_t>(round) * kPhiloxW1;
    }
  }
}

void NormalLanes::block(std::uint64_t first_pair, double* out, std::ptrdiff_t stride) const {
  dispatch::kernels().normal_lanes_block({key0_, key1_, seed_high_, round_keys_}, first_pair, out, stride);
}

double NormalStream::at(std::uint64_t index) const {
  double out[2 * kBlockPairs];
  const std::uint64_t pair = index / 2;
  block(pair - pair % kBlockPairs, out);
  return out[2 * (pair % kBlockPairs) + index % 2];
}

void NormalStream::fill(std::uint64_t first, double* out, std::size_t count) const {
  double buf[2 * kBlockPairs];
  constexpr std::uint64_t kBlockNormals = 2 * kBlockPairs;
  std::uint64_t index = first;
  const std::uint64_t end = first + count;
  while (index < end) {
    const std::uint64_t start = index - index % kBlockNormals;
    const std::uint64_t stop = std::min(end, start + kBlockNormals);
    if (start == index && stop == start + kBlockNormals) {
      block(start / 2, out + (index - first));  // whole block: straight into place
    } else {
      block(start / 2, buf);
      std::copy(buf + (index - start), buf + (stop - start), out + (index - first));
    }
    index = stop;
  }
}

}  // namespace gear_dynamics
