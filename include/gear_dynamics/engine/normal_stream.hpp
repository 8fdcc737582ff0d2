// One counter-based stream of standard normals per realization (doc/model.md §9): Philox4x32-10
// (bit for bit Random123's) keyed by (seed, realization); normal 2p + j is Boost.Random's
// 128-layer ziggurat (normal_distribution<double>) on word j of counter p, its rare retries on
// words of that normal's own retry counters. The ziggurat's first test runs in SIMD,
// kBlockPairs counters at a time, and so does Boost's wedge test for the first test's rejects;
// Boost's code does the rest (the tail, exp between the wedge's bounds, further tries).
// Normal i of a stream depends only on (seed, realization, i), so a realization has the same path
// whatever runs beside it, in whatever order, on however many threads.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gear_dynamics {

class NormalStream {
 public:
  static constexpr int kBlockPairs = 32;  // pairs of normals generated together

  NormalStream(std::uint64_t seed, std::uint64_t realization);

  // Normal number `index` of the stream.
  double at(std::uint64_t index) const;
  // out[k] = at(first + k) for k < count.
  void fill(std::uint64_t first, double* out, std::size_t count) const;

  // Philox4x32-10 output of the counters (p, p >> 32, seed_high, 0) for p = first_pair ...
  // first_pair + kBlockPairs - 1, as the words w0 = out[1]:out[0] and w1 = out[3]:out[2]: the main
  // words of normals 2p and 2p + 1.
  void philox(std::uint64_t first_pair, std::uint64_t* w0, std::uint64_t* w1) const;

 private:
  // Normals 2 first_pair ... 2 (first_pair + kBlockPairs) - 1 into out.
  void block(std::uint64_t first_pair, double* out) const;
  friend class NormalLanes;
  std::uint32_t key_[2];
  std::uint32_t seed_high_;
};

// The streams of kLanes realizations side by side, one per SIMD lane, all lanes at the same counter
// (keys as vectors): lane l gives NormalStream(seed, realization[l])'s normals bit for bit (the same
// Philox counters and keys, the same ziggurat test lane by lane, the same slow path per normal),
// whatever the other lanes hold. Ensemble draws its normals this way, straight into its lane-major
// chunk.
class NormalLanes {
 public:
  static constexpr int kLanes = 8;
  static constexpr int kBlockPairs = NormalStream::kBlockPairs;

  NormalLanes(std::uint64_t seed, const std::uint64_t (&realizations)[kLanes]);

  // Normals 2 first_pair ... 2 (first_pair + kBlockPairs) - 1 of every lane: normal 2 first_pair + k
  // of lane l goes to out[k * stride + l].
  void block(std::uint64_t first_pair, double* out, std::ptrdiff_t stride) const;

 private:
  std::uint32_t key0_[kLanes], key1_[kLanes], seed_high_[kLanes];
  // Each lane's two key words in each of Philox's 10 rounds (32-bit values in 64-bit slots), so
  // that the rounds read them instead of adding the key schedule's steps.
  alignas(64) std::uint64_t round_keys_[10][2][kLanes];
};

}  // namespace gear_dynamics
