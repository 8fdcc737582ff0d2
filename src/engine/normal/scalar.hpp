// The normal generator without SIMD: Philox on one counter per 64-bit word (the same operations
// as the vector variants, lane by lane), the ziggurat's first test word by word, and Boost's code
// for every reject. One of the variants behind normal_stream.cpp (the others: avx512.hpp,
// avx2.hpp); all give the same numbers bit for bit.
#pragma once

#include "common.hpp"

namespace gear_dynamics::normals {

using Words = std::uint64_t;
constexpr int kWordsPerVector = 1;
inline Words words_set1(std::uint64_t x) { return x; }
inline Words words_from_u32(const std::uint32_t* x) { return *x; }
inline Words words_load(const std::uint64_t* x) { return *x; }
inline void words_store(std::uint64_t* x, Words w) { *x = w; }
inline Words words_iota(std::uint64_t first) { return first; }
inline Words high_to_low(Words x) { return x >> 32; }
inline Words mul_low32(Words a, Words b) { return (a & kLow) * (b & kLow); }
inline Words xor3(Words a, Words b, Words c) { return a ^ b ^ c; }
inline Words swap_halves(Words x) { return x >> 32 | x << 32; }
inline Words low_then_high(Words low, Words high) { return (low & kLow) | high << 32; }

}  // namespace gear_dynamics::normals

#include "philox_rounds.hpp"

namespace gear_dynamics::normals {

// The fast path of Boost.Random's 128-layer ziggurat (normal_distribution.hpp, int_float_pair.hpp),
// with Boost's own table, on vectors of 8 words: one 64-bit word gives the sign (bit 0), the layer
// i (bits 1-7) and the uniform r = ((word with bit 11 cleared) >> 8) 2^-56 in [0, 1); x = r x_i is
// accepted if x < x_{i+1}, 97.2 % of the time. The value is Boost's (x sign) 1 + 0, i.e. x or
// 0 - x (so -0 becomes +0). Integer operations, a conversion of a 56-bit integer rounded to nearest
// and two multiplications: the SIMD and the plain loop agree bit for bit.
//
// words[8 v + l] is word l of vector v, for first <= v < last <= first + 8; an accepted normal
// goes to out(v)[l], the index 8 v + l of each other one to rejects, in order (rejects needs room
// for kRejectsSlack more than the count). Returns how many were rejected.
template <class Out>
int ziggurat_fast(const std::uint64_t* words, int first, int last, Out out, std::uint16_t* rejects) {
  int count = 0;
  const double* const table_x = boost::random::detail::normal_table<double>::table_x;
  constexpr std::uint64_t kClearBit11 = ~(std::uint64_t{1} << 11);
  for (int v = first; v < last; ++v) {
    for (int l = 0; l < 8; ++l) {
      const std::uint64_t u = words[8 * v + l];
      const int layer = static_cast<int>(u >> 1 & 0x7F);
      const double r = static_cast<double>((u & kClearBit11) >> 8) * 0x1p-56;
      const double x = r * table_x[layer];
      if (x < table_x[layer + 1])
        out(v)[l] = (u & 1) ? x : 0.0 - x;
      else
        rejects[count++] = static_cast<std::uint16_t>(8 * v + l);
    }
  }
  return count;
}

inline void first_retry_words(Rejected& chunk) { first_retry_words_one_by_one(chunk); }

constexpr bool kSimdWedge = false;
inline std::uint32_t simd_wedge(const Rejected&, double*) { return 0; }

}  // namespace gear_dynamics::normals
