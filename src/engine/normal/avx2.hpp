// The normal generator on AVX2: Philox on 4 counters per vector, the ziggurat's first test on 4
// words, and (with FMA) Boost's wedge test on 4 lanes; the rejects' retry words one counter at a
// time. One of the variants behind normal_stream.cpp (the others: avx512.hpp, scalar.hpp); all give
// the same numbers bit for bit.
#pragma once

#include <immintrin.h>

#include "common.hpp"

namespace gear_dynamics::normals {

using Words = __m256i;
constexpr int kWordsPerVector = 4;
inline Words words_set1(std::uint64_t x) { return _mm256_set1_epi64x(static_cast<long long>(x)); }
inline Words words_from_u32(const std::uint32_t* x) {
  return _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(x)));
}
inline Words words_load(const std::uint64_t* x) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(x)); }
inline void words_store(std::uint64_t* x, Words w) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(x), w); }
inline Words words_iota(std::uint64_t first) { return _mm256_add_epi64(words_set1(first), _mm256_set_epi64x(3, 2, 1, 0)); }
inline Words high_to_low(Words x) { return _mm256_srli_epi64(x, 32); }
inline Words mul_low32(Words a, Words b) { return _mm256_mul_epu32(a, b); }
inline Words xor3(Words a, Words b, Words c) { return _mm256_xor_si256(_mm256_xor_si256(a, b), c); }
inline Words swap_halves(Words x) { return _mm256_shuffle_epi32(x, 0xB1); }
inline Words low_then_high(Words low, Words high) { return _mm256_blend_epi32(low, swap_halves(high), 0xAA); }

}  // namespace gear_dynamics::normals

#include "philox_rounds.hpp"

namespace gear_dynamics::normals {

// 64-bit integers to the nearest doubles, as AVX-512's cvtepu64_pd and the plain loop's cast round
// them: the high and low 32 bits become exact doubles by the 2^84 and 2^52 exponent tricks, and
// their sum is rounded once.
inline __m256d to_double(__m256i n) {
  const __m256d high = _mm256_sub_pd(
      _mm256_castsi256_pd(_mm256_or_si256(_mm256_srli_epi64(n, 32), _mm256_set1_epi64x(0x4530000000000000))),
      _mm256_set1_pd(0x1p84 + 0x1p52));
  return _mm256_add_pd(high, _mm256_castsi256_pd(_mm256_blend_epi32(n, _mm256_set1_epi64x(0x4330000000000000), 0xAA)));
}

// table[i] and table[i + 1] for the layer i (bits 1-7) of each of 4 words, as one 16-byte load
// per lane, transposed (faster than a gather on the AVX2 machines of bench/README.md §1).
inline void table_pairs(const double* table, const std::uint64_t* words, __m256d& at_layer, __m256d& next) {
  const auto pair = [&](int k) { return _mm_loadu_pd(table + (words[k] >> 1 & 0x7F)); };
  const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(pair(0)), pair(2), 1);
  const __m256d b = _mm256_insertf128_pd(_mm256_castpd128_pd256(pair(1)), pair(3), 1);
  at_layer = _mm256_unpacklo_pd(a, b);
  next = _mm256_unpackhi_pd(a, b);
}

// Boost's first test on 4 words (as the AVX-512 first_test_values): x = r x_i, x_i and x_{i+1}.
struct FirstTest4 {
  __m256d x, x_i, x_next;
};
inline FirstTest4 first_test_values(const std::uint64_t* words) {
  const double* const table_x = boost::random::detail::normal_table<double>::table_x;
  constexpr std::uint64_t kClearBit11 = ~(std::uint64_t{1} << 11);
  const __m256i u = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(words));
  const __m256i bits = _mm256_srli_epi64(_mm256_and_si256(u, _mm256_set1_epi64x(static_cast<long long>(kClearBit11))), 8);
  const __m256d r = _mm256_mul_pd(to_double(bits), _mm256_set1_pd(0x1p-56));
  FirstTest4 f;
  table_pairs(table_x, words, f.x_i, f.x_next);
  f.x = _mm256_mul_pd(r, f.x_i);
  return f;
}

// Boost's value for each lane: x where bit 0 of the word is set, else 0 - x.
inline __m256d signed_normal(const std::uint64_t* words, __m256d x) {
  const __m256i u = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(words));
  const __m256i one = _mm256_set1_epi64x(1);
  const __m256d positive = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(u, one), one));
  return _mm256_blendv_pd(_mm256_sub_pd(_mm256_setzero_pd(), x), x, positive);
}

// ziggurat_fast's first test (below) on 4 words: every lane's candidate goes to out, the rejected
// ones to be overwritten by the slow path. Returns which lanes were accepted (bits 0-3).
inline int first_test_4(const std::uint64_t* words, double* out) {
  const FirstTest4 f = first_test_values(words);
  _mm256_storeu_pd(out, signed_normal(words, f.x));
  return _mm256_movemask_pd(_mm256_cmp_pd(f.x, f.x_next, _CMP_LT_OQ));
}

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
  for (int v = first; v < last; ++v) {
    const int accepted = first_test_4(words + 8 * v, out(v)) | first_test_4(words + 8 * v + 4, out(v) + 4) << 4;
    for (unsigned rejected = ~accepted & 0xFFu; rejected != 0; rejected &= rejected - 1)
      rejects[count++] = static_cast<std::uint16_t>(8 * v + __builtin_ctz(rejected));
  }
  return count;
}

inline void first_retry_words(Rejected& chunk) { first_retry_words_one_by_one(chunk); }

#if defined(__FMA__)
// exp_near and wedge above on 4 lanes, for AVX2 (the same operations; 2^k built in the exponent
// field, k in [-12, 0], where AVX-512 has scalef).
inline __m256d exp_near(__m256d a) {
  const __m256d k = _mm256_round_pd(_mm256_mul_pd(a, _mm256_set1_pd(1.4426950408889634)), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  const __m256d r = _mm256_fnmadd_pd(k, _mm256_set1_pd(1.90821492927058770002e-10),
                                     _mm256_fnmadd_pd(k, _mm256_set1_pd(6.93147180369123816490e-01), a));
  __m256d p = _mm256_set1_pd(kTaylor[13]);
  for (int n = 12; n >= 0; --n) p = _mm256_fmadd_pd(p, r, _mm256_set1_pd(kTaylor[n]));
  const __m256i exponent = _mm256_slli_epi64(_mm256_add_epi64(_mm256_cvtepi32_epi64(_mm256_cvtpd_epi32(k)), _mm256_set1_epi64x(1023)), 52);
  return _mm256_mul_pd(p, _mm256_castsi256_pd(exponent));
}

// Slots 4 g ... 4 g + 3 of the chunk (which is zero past its count); returns the decided lanes.
int wedge(const Rejected& chunk, int g, double* value) {
  const double* const table_y = boost::random::detail::normal_table<double>::table_y;
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
  const __m256d filled = _mm256_castsi256_pd(
      _mm256_cmpgt_epi64(_mm256_set1_epi64x(chunk.count - 4 * g), _mm256_set_epi64x(3, 2, 1, 0)));
  const std::uint64_t* const words = chunk.word + 4 * g;
  const FirstTest4 f = first_test_values(words);
  const __m256d x = f.x, x_i = f.x_i, x_next = f.x_next;
  const __m256i layer = _mm256_and_si256(_mm256_srli_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(words)), 1),
                                         _mm256_set1_epi64x(0x7F));
  const __m256d in_wedge = _mm256_andnot_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(layer, _mm256_setzero_si256())), filled);
  const __m256d y01 = _mm256_mul_pd(to_double(_mm256_load_si256(reinterpret_cast<const __m256i*>(chunk.retry0 + 4 * g))),
                                    _mm256_set1_pd(0x1p-64));
  const __m256d uniform = _mm256_and_pd(in_wedge, _mm256_cmp_pd(y01, one, _CMP_LT_OQ));
  __m256d y_i, y_next;
  table_pairs(table_y, words, y_i, y_next);
  const __m256d y = _mm256_add_pd(y_i, _mm256_mul_pd(y01, _mm256_sub_pd(y_next, y_i)));
  const __m256d x_i_minus_x = _mm256_sub_pd(x_i, x);
  const __m256d chord = _mm256_sub_pd(_mm256_mul_pd(_mm256_sub_pd(x_i, x_next), y01), x_i_minus_x);
  const __m256d tangent = _mm256_sub_pd(y, _mm256_add_pd(y_i, _mm256_mul_pd(_mm256_mul_pd(x_i_minus_x, y_i), x_i)));
  const __m256d convex = _mm256_cmp_pd(x_i, one, _CMP_GE_OQ);
  const __m256d above_ubound = _mm256_blendv_pd(tangent, chord, convex);
  const __m256d above_lbound = _mm256_blendv_pd(chord, tangent, convex);
  const __m256d below_ubound = _mm256_and_pd(uniform, _mm256_cmp_pd(above_ubound, zero, _CMP_LT_OQ));
  const __m256d below_lbound = _mm256_and_pd(below_ubound, _mm256_cmp_pd(above_lbound, zero, _CMP_LT_OQ));
  const __m256d between = _mm256_andnot_pd(below_lbound, below_ubound);
  const __m256d curve = exp_near(_mm256_sub_pd(zero, _mm256_div_pd(_mm256_mul_pd(x, x), _mm256_set1_pd(2.0))));
  const __m256d below_curve = _mm256_and_pd(between, _mm256_cmp_pd(y, _mm256_mul_pd(curve, _mm256_set1_pd(1 - 1e-12)), _CMP_LT_OQ));
  const __m256d above_curve = _mm256_and_pd(between, _mm256_cmp_pd(y, _mm256_mul_pd(curve, _mm256_set1_pd(1 + 1e-12)), _CMP_GT_OQ));
  const __m256d accepted = _mm256_or_pd(below_lbound, below_curve);
  const __m256d rejected = _mm256_or_pd(_mm256_andnot_pd(below_ubound, uniform), above_curve);
  // Boost's next try: w1 is its main word.
  const std::uint64_t* const words2 = chunk.retry1 + 4 * g;
  const FirstTest4 f2 = first_test_values(words2);
  const __m256d retried = _mm256_and_pd(rejected, _mm256_cmp_pd(f2.x, f2.x_next, _CMP_LT_OQ));
  _mm256_storeu_pd(value + 4 * g, _mm256_blendv_pd(signed_normal(words2, f2.x), signed_normal(words, x), accepted));
  return _mm256_movemask_pd(_mm256_or_pd(accepted, retried));
}

constexpr bool kSimdWedge = true;
inline std::uint32_t simd_wedge(const Rejected& chunk, double* value) {
  std::uint32_t decided = 0;
  for (int g = 0; 4 * g < chunk.count; ++g) decided |= static_cast<std::uint32_t>(wedge(chunk, g, value)) << (4 * g);
  return decided;
}
#else
// exp_near is written in fused multiply-adds: without FMA, Boost's code decides every reject.
constexpr bool kSimdWedge = false;
inline std::uint32_t simd_wedge(const Rejected&, double*) { return 0; }
#endif

}  // namespace gear_dynamics::normals
