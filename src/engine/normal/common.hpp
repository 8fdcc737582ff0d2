// The normal generator's parts that every instruction-set variant shares (src/engine/normal/):
// Philox4x32-10's constants and its one-counter reference, the chunk of rejected normals that the
// slow path works on, and the Taylor coefficients of the wedge tests. Included by normal_stream.cpp
// through exactly one variant header (avx512.hpp, avx2.hpp, scalar.hpp).
#pragma once

#include <boost/random/normal_distribution.hpp>

#include <algorithm>
#include <cstdint>

#include "gear_dynamics/engine/normal_stream.hpp"

namespace gear_dynamics::normals {

constexpr int kBlockPairs = NormalStream::kBlockPairs;

// Philox4x32-10 (Salmon et al. 2011) constants, as in Random123's philox.h.
constexpr std::uint32_t kPhiloxM0 = 0xD2511F53u, kPhiloxM1 = 0xCD9E8D57u;
constexpr std::uint32_t kPhiloxW0 = 0x9E3779B9u, kPhiloxW1 = 0xBB67AE85u;
constexpr std::uint64_t kLow = 0xFFFFFFFFull;  // a 32-bit word held in 64 bits

// 1/n! for n = 0 ... 13: the Taylor coefficients of the wedge tests' exp_near.
struct InverseFactorials {
  double value[14];
  constexpr InverseFactorials() : value{1.0} {
    for (int n = 1; n < 14; ++n) value[n] = value[n - 1] / n;
  }
  constexpr double operator[](int n) const { return value[n]; }
};
[[maybe_unused]] constexpr InverseFactorials kTaylor;

// Philox4x32-10 of one counter (p, p >> 32, seed_high, c3) with key (k0, k1), as the words
// w0 = out[1]:out[0] and w1 = out[3]:out[2]: the reference the SIMD paths must equal (c3 = 0), and
// the retry words of the ziggurat's slow path (c3 > 0).
inline void philox_one(std::uint64_t p, std::uint32_t seed_high, std::uint32_t c3_word, std::uint32_t k0,
                       std::uint32_t k1, std::uint64_t& w0, std::uint64_t& w1) {
  std::uint64_t c0 = p & kLow, c1 = p >> 32, c2 = seed_high, c3 = c3_word;
  for (int round = 0; round < 10; ++round) {
    const std::uint64_t p0 = c0 * kPhiloxM0, p1 = c2 * kPhiloxM1;
    c0 = (p1 >> 32) ^ c1 ^ k0;
    c1 = p1 & kLow;
    c2 = (p0 >> 32) ^ c3 ^ k1;
    c3 = p0 & kLow;
    k0 += kPhiloxW0;
    k1 += kPhiloxW1;
  }
  w0 = (c1 << 32) | c0;
  w1 = (c3 << 32) | c2;
}

// Philox4x32-10 on several counters side by side in a vector of 64-bit lanes (8 with AVX-512, 4

// How many slots past the count ziggurat_fast may write into `rejects` (whole-vector stores).
constexpr int kRejectsSlack = 32;

// Up to kChunk normals the fast path rejected. Slot i is normal k = 2p + j of the stream with
// key (k0, k1) and counter word seed_high, whose main word (word j of counter
// (p, p >> 32, seed_high, 0)) is word; c3 = 1 + j is its first retry counter's last word.
// first_retry_words(Rejected&), one per variant, fills retry0 and retry1.
struct Rejected {
  static constexpr int kChunk = 16;
  std::uint64_t word[kChunk], p[kChunk];
  std::uint32_t c3[kChunk], seed_high[kChunk], k0[kChunk], k1[kChunk];
  double* out[kChunk];
  // The words of counter (p, p >> 32, seed_high, c3) of each slot, for slots 0 ... count - 1.
  alignas(64) std::uint64_t retry0[kChunk], retry1[kChunk];
  int count = 0;

  void add(std::uint64_t main_word, std::uint64_t pair, int j, std::uint32_t seed_hi, std::uint32_t key0,
           std::uint32_t key1, double* normal) {
    word[count] = main_word;
    p[count] = pair;
    c3[count] = 1u + static_cast<std::uint32_t>(j);
    seed_high[count] = seed_hi;
    k0[count] = key0;
    k1[count] = key1;
    out[count++] = normal;
  }
};

// The words of each slot's first retry counter, one counter at a time (the variants without a
// per-lane SIMD Philox).
inline void first_retry_words_one_by_one(Rejected& chunk) {
  for (int i = 0; i < chunk.count; ++i)
    philox_one(chunk.p[i], chunk.seed_high[i], chunk.c3[i], chunk.k0[i], chunk.k1[i], chunk.retry0[i], chunk.retry1[i]);
}

}  // namespace gear_dynamics::normals
