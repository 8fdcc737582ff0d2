// The normal generator on AVX-512 (F, DQ, VL; VBMI2 where the CPU has it): Philox on 8 counters per
// vector, the ziggurat's first test on 8 words, the rejects' retry words by a per-lane Philox and
// Boost's wedge test on 8 lanes. One of the variants behind normal_stream.cpp (the others:
// avx2.hpp, scalar.hpp); all give the same numbers bit for bit.
#pragma once

#include <immintrin.h>

#include "common.hpp"

namespace gear_dynamics::normals {

using Words = __m512i;
constexpr int kWordsPerVector = 8;
inline Words words_set1(std::uint64_t x) { return _mm512_set1_epi64(static_cast<long long>(x)); }
inline Words words_from_u32(const std::uint32_t* x) {  // zero-extended
  return _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(x)));
}
inline Words words_load(const std::uint64_t* x) { return _mm512_loadu_si512(x); }
inline void words_store(std::uint64_t* x, Words w) { _mm512_storeu_si512(x, w); }
inline Words words_iota(std::uint64_t first) {  // first, first + 1, ...
  return _mm512_add_epi64(words_set1(first), _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0));
}
inline Words high_to_low(Words x) { return _mm512_srli_epi64(x, 32); }
inline Words mul_low32(Words a, Words b) { return _mm512_mul_epu32(a, b); }
inline Words xor3(Words a, Words b, Words c) { return _mm512_xor_si512(_mm512_xor_si512(a, b), c); }
inline Words swap_halves(Words x) { return _mm512_shuffle_epi32(x, _MM_PERM_CDAB); }
inline Words low_then_high(Words low, Words high) {  // each lane: high's low dword : low's low dword
  return _mm512_mask_blend_epi32(0xAAAA, low, swap_halves(high));
}

}  // namespace gear_dynamics::normals

#include "philox_rounds.hpp"

namespace gear_dynamics::normals {

// Boost's first test on 8 words u (layer = bits 1-7, r = (u & ~bit 11) >> 8 times 2^-56): the layer,
// x = r x_i, and x_i, x_{i+1} of the layer; the test accepts where x < x_{i+1}.
inline void first_test_values(__m512i u, __m512i& layer, __m512d& x, __m512d& x_i, __m512d& x_next) {
  const double* const table_x = boost::random::detail::normal_table<double>::table_x;
  constexpr std::uint64_t kClearBit11 = ~(std::uint64_t{1} << 11);
  layer = _mm512_and_si512(_mm512_srli_epi64(u, 1), _mm512_set1_epi64(0x7F));
  const __m512i bits = _mm512_srli_epi64(_mm512_and_si512(u, _mm512_set1_epi64(static_cast<long long>(kClearBit11))), 8);
  const __m512d r = _mm512_mul_pd(_mm512_cvtepu64_pd(bits), _mm512_set1_pd(0x1p-56));
  x_i = _mm512_i64gather_pd(layer, table_x, 8);
  x_next = _mm512_i64gather_pd(layer, table_x + 1, 8);
  x = _mm512_mul_pd(r, x_i);
}

// The first test on 8 words; the accepted lanes' normals (sign = bit 0) go to out. Returns which
// lanes were accepted.
inline __mmask8 first_test_8(const std::uint64_t* words, double* out) {
  const __m512i u = _mm512_loadu_si512(words);
  __m512i layer;
  __m512d x, x_i, x_next;
  first_test_values(u, layer, x, x_i, x_next);
  const __mmask8 accepted = _mm512_cmp_pd_mask(x, x_next, _CMP_LT_OQ);
  const __mmask8 negative = _mm512_testn_epi64_mask(u, _mm512_set1_epi64(1));
  _mm512_mask_storeu_pd(out, accepted, _mm512_mask_sub_pd(x, negative, _mm512_setzero_pd(), x));
  return accepted;
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
#if defined(__AVX512VBMI2__)
  // Each vector's rejected lanes as one byte of a 64-bit mask; their indices packed at the end by
  // two compressions of 32 16-bit lanes (in registers, stored whole: a compressing store to memory
  // is microcoded and slow). No branch on data that is random by design.
  std::uint64_t rejected = 0;
  for (int v = first; v < last; ++v) {
    const __mmask8 accepted = first_test_8(words + 8 * v, out(v));
    rejected |= std::uint64_t{static_cast<std::uint8_t>(~accepted)} << (8 * (v - first));
  }
  const __m512i index = _mm512_add_epi16(
      _mm512_set1_epi16(static_cast<short>(8 * first)),
      _mm512_set_epi16(31, 30, 29, 28, 27, 26, 25, 24, 23, 22, 21, 20, 19, 18, 17, 16, 15, 14, 13, 12, 11, 10, 9, 8,
                       7, 6, 5, 4, 3, 2, 1, 0));
  for (int half = 0; half < 2; ++half) {
    const auto lanes = static_cast<__mmask32>(rejected >> (32 * half));
    _mm512_storeu_si512(rejects + count,
                        _mm512_maskz_compress_epi16(lanes, _mm512_add_epi16(index, _mm512_set1_epi16(static_cast<short>(32 * half)))));
    count += __builtin_popcount(lanes);
  }
#else
  const __m512i lane = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0);
  for (int v = first; v < last; ++v) {
    const __mmask8 accepted = first_test_8(words + 8 * v, out(v));
    // The rejected lanes' indices, packed in a register and stored whole (a compressing store to
    // memory is microcoded and slow): no branch on data that is random by design.
    const __mmask8 rejected = static_cast<__mmask8>(~accepted);
    const __m512i index = _mm512_maskz_compress_epi64(rejected, _mm512_add_epi64(_mm512_set1_epi64(8 * v), lane));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(rejects + count), _mm512_cvtepi64_epi16(index));
    count += __builtin_popcount(rejected);
  }
#endif
  return count;
}

// Philox4x32-10 with counters and keys per lane on slots 0 ... 8 G - 1 of the chunk (those past
// count read as zeros; their words are not used), as in NormalLanes::block.
template <int G>
void first_retry_words(Rejected& chunk) {
  static_assert(8 * G <= Rejected::kChunk);
  const __m512i w0_step = _mm512_set1_epi64(kPhiloxW0), w1_step = _mm512_set1_epi64(kPhiloxW1);
  __m512i c0[G], c1[G], c2[G], c3v[G], key0[G], key1[G];
  for (int g = 0; g < G; ++g) {
    const __mmask8 filled = static_cast<__mmask8>((1u << std::clamp(chunk.count - 8 * g, 0, 8)) - 1);
    const auto load32 = [filled](const std::uint32_t* x) {
      return _mm512_cvtepu32_epi64(_mm256_maskz_loadu_epi32(filled, x));
    };
    c0[g] = _mm512_maskz_loadu_epi64(filled, chunk.p + 8 * g);  // vpmuludq ignores its high half
    c1[g] = _mm512_srli_epi64(c0[g], 32);
    c2[g] = load32(chunk.seed_high + 8 * g);
    c3v[g] = load32(chunk.c3 + 8 * g);
    key0[g] = load32(chunk.k0 + 8 * g);
    key1[g] = load32(chunk.k1 + 8 * g);
  }
  for (int round = 0; round < 10; ++round) {
    for (int g = 0; g < G; ++g) {
      philox_round(c0[g], c1[g], c2[g], c3v[g], key0[g], key1[g]);
      key0[g] = _mm512_add_epi32(key0[g], w0_step);
      key1[g] = _mm512_add_epi32(key1[g], w1_step);
    }
  }
  for (int g = 0; g < G; ++g) {
    __m512i w0, w1;
    philox_words(c0[g], c1[g], c2[g], c3v[g], w0, w1);
    _mm512_store_si512(chunk.retry0 + 8 * g, w0);
    _mm512_store_si512(chunk.retry1 + 8 * g, w1);
  }
}

inline void first_retry_words(Rejected& chunk) {
  if (chunk.count <= 8)
    first_retry_words<1>(chunk);
  else
    first_retry_words<2>(chunk);
}

// Boost.Random's wedge test, evaluated in SIMD on the slots 8 g ... 8 g + 7 of a chunk whose first
// retry words are computed: Boost's algorithm (unit_normal_distribution::operator() in
// normal_distribution.hpp, the reference test_random compares every normal with) from the point
// where the main word failed the first test, with the same IEEE operations in the same order, so
// the same doubles (the build contracts nothing). For layer i >= 1, y01 = uniform_01 on retry word
// w0 and y = y_i + y01 (y_{i+1} - y_i); the chord and tangent bounds accept or reject, and between
// them the comparison with e^{-x^2/2}, where an approximation decides it. A rejected normal tries
// again on w1 as its main word: the first test accepts it (97 %) or Boost takes over. Boost's own
// code stays the fallback where these do not decide: the tail (layer 0), a second rejection, y
// within 1e-12 relative of e^{-x^2/2}, or uniform_01 drawing again (w0 rounding to 2^64). Stores
// the decided normals to value[8 g + l] and returns which lanes they are.
// e^a for -8 < a <= 0 within about 1e-15 relative (a = k ln 2 + r, |r| <= ln 2 / 2, by Cody and
// Waite's two-part ln 2; e^r by its Taylor polynomial to degree 13, whose remainder is below
// 1e-17): not glibc's exp, only close enough to tell on which side of it a number 1e-12 away lies.
inline __m512d exp_near(__m512d a) {
  const __m512d k = _mm512_roundscale_pd(_mm512_mul_pd(a, _mm512_set1_pd(1.4426950408889634)), _MM_FROUND_TO_NEAREST_INT);
  const __m512d r = _mm512_fnmadd_pd(k, _mm512_set1_pd(1.90821492927058770002e-10),  // ln 2 - ln2_hi
                                     _mm512_fnmadd_pd(k, _mm512_set1_pd(6.93147180369123816490e-01), a));  // ln2_hi: k ln2_hi is exact
  __m512d p = _mm512_set1_pd(kTaylor[13]);
  for (int n = 12; n >= 0; --n) p = _mm512_fmadd_pd(p, r, _mm512_set1_pd(kTaylor[n]));
  return _mm512_scalef_pd(p, k);
}

__mmask8 wedge(const Rejected& chunk, int g, double* value) {
  const double* const table_y = boost::random::detail::normal_table<double>::table_y;
  const __mmask8 filled = static_cast<__mmask8>((1u << std::clamp(chunk.count - 8 * g, 0, 8)) - 1);
  const __m512i one = _mm512_set1_epi64(1);
  const __m512i u = _mm512_maskz_loadu_epi64(filled, chunk.word + 8 * g);  // slots past count: zeros
  __m512i layer;
  __m512d x, x_i, x_next;
  first_test_values(u, layer, x, x_i, x_next);
  const __mmask8 in_wedge = _mm512_mask_test_epi64_mask(filled, layer, layer);  // layer >= 1
  // uniform_01 on a 64-bit engine: word (rounded to nearest) / 2^64, drawn again if it gives 1.
  const __m512d y01 = _mm512_mul_pd(_mm512_cvtepu64_pd(_mm512_load_si512(chunk.retry0 + 8 * g)), _mm512_set1_pd(0x1p-64));
  const __mmask8 uniform = _mm512_mask_cmp_pd_mask(in_wedge, y01, _mm512_set1_pd(1.0), _CMP_LT_OQ);
  const __m512d y_i = _mm512_i64gather_pd(layer, table_y, 8);
  const __m512d y_next = _mm512_i64gather_pd(layer, table_y + 1, 8);
  const __m512d y = _mm512_add_pd(y_i, _mm512_mul_pd(y01, _mm512_sub_pd(y_next, y_i)));
  const __m512d x_i_minus_x = _mm512_sub_pd(x_i, x);
  const __m512d chord = _mm512_sub_pd(_mm512_mul_pd(_mm512_sub_pd(x_i, x_next), y01), x_i_minus_x);
  const __m512d tangent =
      _mm512_sub_pd(y, _mm512_add_pd(y_i, _mm512_mul_pd(_mm512_mul_pd(x_i_minus_x, y_i), x_i)));
  // Convex layers (x_i >= 1): y_above_ubound is the chord's, y_above_lbound the tangent's; concave
  // the other way round.
  const __mmask8 convex = _mm512_cmp_pd_mask(x_i, _mm512_set1_pd(1.0), _CMP_GE_OQ);
  const __m512d above_ubound = _mm512_mask_blend_pd(convex, tangent, chord);
  const __m512d above_lbound = _mm512_mask_blend_pd(convex, chord, tangent);
  const __mmask8 below_ubound = _mm512_mask_cmp_pd_mask(uniform, above_ubound, _mm512_setzero_pd(), _CMP_LT_OQ);
  const __mmask8 below_lbound = _mm512_mask_cmp_pd_mask(below_ubound, above_lbound, _mm512_setzero_pd(), _CMP_LT_OQ);
  // Between the bounds Boost accepts if y < exp(-(x x / 2)) (glibc's exp); exp_near decides it where
  // y is further than 1e-12 relative from the curve, far beyond both functions' errors.
  const __mmask8 between = static_cast<__mmask8>(below_ubound & ~below_lbound);
  const __m512d curve = exp_near(_mm512_sub_pd(_mm512_setzero_pd(), _mm512_div_pd(_mm512_mul_pd(x, x), _mm512_set1_pd(2.0))));
  const __mmask8 below_curve = _mm512_mask_cmp_pd_mask(between, y, _mm512_mul_pd(curve, _mm512_set1_pd(1 - 1e-12)), _CMP_LT_OQ);
  const __mmask8 above_curve = _mm512_mask_cmp_pd_mask(between, y, _mm512_mul_pd(curve, _mm512_set1_pd(1 + 1e-12)), _CMP_GT_OQ);
  const __mmask8 accepted = below_lbound | below_curve;
  const __mmask8 rejected = static_cast<__mmask8>((uniform & ~below_ubound) | above_curve);
  // Boost's next try: w1 is its main word.
  const __m512i u2 = _mm512_load_si512(chunk.retry1 + 8 * g);
  __m512i layer2;
  __m512d x2, x2_i, x2_next;
  first_test_values(u2, layer2, x2, x2_i, x2_next);
  const __mmask8 retried = _mm512_mask_cmp_pd_mask(rejected, x2, x2_next, _CMP_LT_OQ);
  // Boost's (x sign) 1 + 0 as in ziggurat_fast, with the sign of the accepted word.
  const __m512d chosen = _mm512_mask_blend_pd(accepted, x2, x);
  const __mmask8 negative =
      (_mm512_testn_epi64_mask(u, one) & accepted) | (_mm512_testn_epi64_mask(u2, one) & retried);
  _mm512_storeu_pd(value + 8 * g, _mm512_mask_sub_pd(chosen, negative, _mm512_setzero_pd(), chosen));
  return accepted | retried;
}

// The wedge test on the chunk's slots (wedge() on 8 lanes at a time): the normals it decides go to
// value[i], the mask of which slots they are is returned.
constexpr bool kSimdWedge = true;
inline std::uint32_t simd_wedge(const Rejected& chunk, double* value) {
  std::uint32_t decided = wedge(chunk, 0, value);
  if (chunk.count > 8) decided |= std::uint32_t{wedge(chunk, 1, value)} << 8;
  return decided;
}

}  // namespace gear_dynamics::normals
