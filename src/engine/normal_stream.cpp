#include "gear_dynamics/engine/normal_stream.hpp"

#include <boost/random/normal_distribution.hpp>
#include <immintrin.h>
#include <algorithm>

namespace gear_dynamics {

namespace {

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
// with AVX2), one 32-bit word of the state in the low half of each lane. vpmuludq reads only the
// low halves, so the high halves may carry junk through the rounds; philox_words clears them. A
// product's high half moves down by swapping the dwords of each lane (vpshufd, a shuffle) rather
// than by a shift, which would compete with the multiplies for the port that runs both on 512-bit
// vectors.
#if defined(__AVX512F__)
#define GD_PHILOX_SIMD 1
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
#elif defined(__AVX2__)
#define GD_PHILOX_SIMD 1
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
#endif

#ifdef GD_PHILOX_SIMD
inline void philox_round(Words& c0, Words& c1, Words& c2, Words& c3, Words key0, Words key1) {
  const Words p0 = mul_low32(c0, words_set1(kPhiloxM0));
  const Words p1 = mul_low32(c2, words_set1(kPhiloxM1));
  c0 = xor3(swap_halves(p1), c1, key0);
  c1 = p1;
  c2 = xor3(swap_halves(p0), c3, key1);
  c3 = p0;
}

// The state's words as the 64-bit outputs w0 = c1:c0 and w1 = c3:c2.
inline void philox_words(Words c0, Words c1, Words c2, Words c3, Words& w0, Words& w1) {
  w0 = low_then_high(c0, c1);
  w1 = low_then_high(c2, c3);
}
#endif

#ifdef __AVX512DQ__
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
#elif defined(__AVX2__)
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
#endif

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
constexpr int kRejectsSlack = 32;
template <class Out>
int ziggurat_fast(const std::uint64_t* words, int first, int last, Out out, std::uint16_t* rejects) {
  int count = 0;
#if defined(__AVX512DQ__) && defined(__AVX512VBMI2__)
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
#elif defined(__AVX512DQ__)
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
#elif defined(__AVX2__)
  for (int v = first; v < last; ++v) {
    const int accepted = first_test_4(words + 8 * v, out(v)) | first_test_4(words + 8 * v + 4, out(v) + 4) << 4;
    for (unsigned rejected = ~accepted & 0xFFu; rejected != 0; rejected &= rejected - 1)
      rejects[count++] = static_cast<std::uint16_t>(8 * v + __builtin_ctz(rejected));
  }
#else
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
#endif
  return count;
}

// Up to kChunk normals the fast path rejected. Slot i is normal k = 2p + j of the stream with
// key (k0, k1) and counter word seed_high, whose main word (word j of counter
// (p, p >> 32, seed_high, 0)) is word; c3 = 1 + j is its first retry counter's last word.
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

  // The words of each slot's first retry counter into retry0, retry1.
  void first_retry_words() {
#ifdef __AVX512VL__
    if (count <= 8)
      first_retry_words<1>();
    else
      first_retry_words<2>();
#else
    for (int i = 0; i < count; ++i) philox_one(p[i], seed_high[i], c3[i], k0[i], k1[i], retry0[i], retry1[i]);
#endif
  }

#ifdef __AVX512VL__
  // Philox4x32-10 with counters and keys per lane on slots 0 ... 8 G - 1 (those past count read
  // as zeros; their words are not used), as in NormalLanes::block.
  template <int G>
  void first_retry_words() {
    static_assert(8 * G <= kChunk);
    const __m512i w0_step = _mm512_set1_epi64(kPhiloxW0), w1_step = _mm512_set1_epi64(kPhiloxW1);
    __m512i c0[G], c1[G], c2[G], c3v[G], key0[G], key1[G];
    for (int g = 0; g < G; ++g) {
      const __mmask8 filled = static_cast<__mmask8>((1u << std::clamp(count - 8 * g, 0, 8)) - 1);
      const auto load32 = [filled](const std::uint32_t* x) {
        return _mm512_cvtepu32_epi64(_mm256_maskz_loadu_epi32(filled, x));
      };
      c0[g] = _mm512_maskz_loadu_epi64(filled, p + 8 * g);  // vpmuludq ignores its high half
      c1[g] = _mm512_srli_epi64(c0[g], 32);
      c2[g] = load32(seed_high + 8 * g);
      c3v[g] = load32(c3 + 8 * g);
      key0[g] = load32(k0 + 8 * g);
      key1[g] = load32(k1 + 8 * g);
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
      _mm512_store_si512(retry0 + 8 * g, w0);
      _mm512_store_si512(retry1 + 8 * g, w1);
    }
  }
#endif
};

// The 64-bit engine Boost.Random's normal_distribution draws rejected normal i from: first the
// main word, then the words of the retry counters (p, p >> 32, seed_high, 1 + j + 2m) for
// m = 0, 1, ..., each giving w0 then w1. Those of m = 0 (all that 98.6 % of the slow normals need)
// come precomputed, the others are computed when asked for.
class ReplayEngine {
 public:
  using result_type = std::uint64_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }

  ReplayEngine(const Rejected& rejected, int i)
      : normals_(rejected), i_(i), retry_{rejected.retry0[i], rejected.retry1[i]} {}

  result_type operator()() {
    const unsigned n = drawn_++;
    if (n == 0) return normals_.word[i_];
    if (n >= 3 && n % 2 == 1)  // word 0 of retry counter m = (n - 1) / 2 >= 1, c3 = 1 + j + 2m
      philox_one(normals_.p[i_], normals_.seed_high[i_], normals_.c3[i_] + (n - 1), normals_.k0[i_], normals_.k1[i_],
                 retry_[0], retry_[1]);
    return retry_[(n - 1) % 2];
  }

 private:
  const Rejected& normals_;
  int i_;
  std::uint64_t retry_[2];
  unsigned drawn_ = 0;
};

#ifdef __AVX512DQ__
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
#elif defined(__AVX2__) && defined(__FMA__)
#define GD_SIMD_WEDGE 1
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
#endif

// The slow path for the rejects of ziggurat_fast (add(index, chunk) puts each into a chunk),
// kChunk at a time so that their first retry words come from one SIMD Philox: Boost's wedge test
// in SIMD (wedge() above) with AVX-512 or AVX2 and FMA, and Boost.Random's normal_distribution<double>(0, 1)
// in full on the engine of each normal it does not decide (it repeats the first test on the main
// word and goes on to the wedge or the tail).
template <class Add>
void slow_normals(const std::uint16_t* rejects, int count, Add add) {
  for (int start = 0; start < count; start += Rejected::kChunk) {
    Rejected chunk{};  // zeros past its count, where the SIMD wedge reads whole vectors
    for (int n = start; n < std::min(count, start + Rejected::kChunk); ++n) add(rejects[n], chunk);
    chunk.first_retry_words();
    std::uint32_t undecided = (1u << chunk.count) - 1;
#if defined(__AVX512DQ__)
    double value[Rejected::kChunk];
    std::uint32_t decided = wedge(chunk, 0, value);
    if (chunk.count > 8) decided |= std::uint32_t{wedge(chunk, 1, value)} << 8;
#elif defined(GD_SIMD_WEDGE)
    double value[Rejected::kChunk];
    std::uint32_t decided = 0;
    for (int g = 0; 4 * g < chunk.count; ++g) decided |= static_cast<std::uint32_t>(wedge(chunk, g, value)) << (4 * g);
#endif
#if defined(__AVX512DQ__) || defined(GD_SIMD_WEDGE)
    for (int i = 0; i < chunk.count; ++i) *chunk.out[i] = value[i];  // the undecided are overwritten below
    undecided &= ~decided;
#endif
    for (; undecided != 0; undecided &= undecided - 1) {
      const int i = __builtin_ctz(undecided);
      ReplayEngine engine(chunk, i);
      *chunk.out[i] = boost::random::normal_distribution<double>(0.0, 1.0)(engine);
    }
  }
}

}  // namespace

NormalStream::NormalStream(std::uint64_t seed, std::uint64_t realization)
    : key_{static_cast<std::uint32_t>(realization), static_cast<std::uint32_t>(seed)},
      seed_high_(static_cast<std::uint32_t>(seed >> 32)) {
  // The high realization bits share the counter word with the seed's high bits; 2^32
  // realizations per seed are far beyond any batch.
  seed_high_ ^= static_cast<std::uint32_t>(realization >> 32) * 0x9E3779B9u;
}

void NormalStream::philox(std::uint64_t first_pair, std::uint64_t* w0, std::uint64_t* w1) const {
  // Philox4x32-10 on the counters (p, p >> 32, seed_high, 0) for kBlockPairs consecutive p, run
  // side by side. Random123's implementation works one counter at a time and compilers turn its
  // 32 x 32 -> 64 bit products into slow 64-bit vector multiplies, hence the SIMD path (AVX-512 or
  // AVX2); both paths are integer arithmetic, so they agree bit for bit (test_random checks both
  // against r123::Philox4x32).
  int i = 0;
#ifdef GD_PHILOX_SIMD
  // kGroups vectors of counters advance together: the rounds are a latency chain, and
  // independent chains side by side keep the multipliers busy.
  constexpr int kGroups = 4, kWidth = kWordsPerVector;
  for (; i + kWidth * kGroups <= kBlockPairs; i += kWidth * kGroups) {
    Words c0[kGroups], c1[kGroups], c2[kGroups], c3[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      c0[g] = words_iota(first_pair + static_cast<std::uint64_t>(i + kWidth * g));
      c1[g] = high_to_low(c0[g]);
      c2[g] = words_set1(seed_high_);
      c3[g] = words_set1(0);
    }
    std::uint32_t k0 = key_[0], k1 = key_[1];
    for (int round = 0; round < 10; ++round) {
      for (int g = 0; g < kGroups; ++g) philox_round(c0[g], c1[g], c2[g], c3[g], words_set1(k0), words_set1(k1));
      k0 += kPhiloxW0;
      k1 += kPhiloxW1;
    }
    for (int g = 0; g < kGroups; ++g) {
      Words word0, word1;
      philox_words(c0[g], c1[g], c2[g], c3[g], word0, word1);
      words_store(w0 + i + kWidth * g, word0);
      words_store(w1 + i + kWidth * g, word1);
    }
  }
#endif
  for (; i < kBlockPairs; ++i)
    philox_one(first_pair + static_cast<std::uint64_t>(i), seed_high_, 0u, key_[0], key_[1], w0[i], w1[i]);
}

void NormalStream::block(std::uint64_t first_pair, double* out) const {
  // words[j][i]: word j of counter first_pair + i, i.e. the main word of normal 2 (first_pair + i) + j.
  alignas(64) std::uint64_t words[2][kBlockPairs];
  philox(first_pair, words[0], words[1]);
  alignas(64) double normals[2][kBlockPairs];
  constexpr int kVectors = 2 * kBlockPairs / 8;
  static_assert(kVectors <= 8, "ziggurat_fast takes up to 8 vectors at a time");
  std::uint16_t rejects[2 * kBlockPairs + kRejectsSlack];
  const int count = ziggurat_fast(&words[0][0], 0, kVectors, [&](int v) { return &normals[0][0] + 8 * v; }, rejects);
  slow_normals(rejects, count, [&](int index, Rejected& chunk) {
    const int j = index / kBlockPairs, i = index % kBlockPairs;
    chunk.add(words[j][i], first_pair + static_cast<std::uint64_t>(i), j, seed_high_, key_[0], key_[1], &normals[j][i]);
  });
  for (int i = 0; i < kBlockPairs; ++i) {
    out[2 * i] = normals[0][i];
    out[2 * i + 1] = normals[1][i];
  }
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
  // kGroups counters at a time, each in kLanes / kWordsPerVector vectors: four independent Philox
  // chains side by side.
#ifdef GD_PHILOX_SIMD
  constexpr int kVectors = kLanes / kWordsPerVector, kGroups = 4 / kVectors;
#else
  constexpr int kGroups = 4;
#endif
  static_assert(kBlockPairs % kGroups == 0 && 2 * kGroups <= 8);  // ziggurat_fast: up to 8 vectors at a time
  // words[i][j][l]: word j of counter first_pair + i of lane l, the main word of the lane's normal
  // k = 2 (first_pair + i) + j, which goes to out[k * stride + l]; vector k of 8 words.
  alignas(64) std::uint64_t words[kBlockPairs][2][kLanes];
  std::uint16_t rejects[2 * kBlockPairs * kLanes + kRejectsSlack];
  int count = 0;
  const auto normals = [&](int k) { return out + k * stride; };
  for (int i = 0; i < kBlockPairs; i += kGroups) {
#ifdef GD_PHILOX_SIMD
    // NormalStream::philox with the counter the same in every lane and the keys per lane.
    Words c0[kGroups][kVectors], c1[kGroups][kVectors], c2[kGroups][kVectors], c3[kGroups][kVectors];
    for (int g = 0; g < kGroups; ++g) {
      const std::uint64_t p = first_pair + static_cast<std::uint64_t>(i + g);
      for (int v = 0; v < kVectors; ++v) {
        c0[g][v] = words_set1(p & kLow);
        c1[g][v] = words_set1(p >> 32);
        c2[g][v] = words_from_u32(seed_high_ + kWordsPerVector * v);
        c3[g][v] = words_set1(0);
      }
    }
    for (int round = 0; round < 10; ++round) {
      for (int v = 0; v < kVectors; ++v) {
        const Words key0 = words_load(round_keys_[round][0] + kWordsPerVector * v);
        const Words key1 = words_load(round_keys_[round][1] + kWordsPerVector * v);
        for (int g = 0; g < kGroups; ++g) philox_round(c0[g][v], c1[g][v], c2[g][v], c3[g][v], key0, key1);
      }
    }
    for (int g = 0; g < kGroups; ++g) {
      for (int v = 0; v < kVectors; ++v) {
        Words w0, w1;
        philox_words(c0[g][v], c1[g][v], c2[g][v], c3[g][v], w0, w1);
        words_store(words[i + g][0] + kWordsPerVector * v, w0);
        words_store(words[i + g][1] + kWordsPerVector * v, w1);
      }
    }
#else
    for (int g = 0; g < kGroups; ++g) {
      for (int l = 0; l < kLanes; ++l)
        philox_one(first_pair + static_cast<std::uint64_t>(i + g), seed_high_[l], 0u, key0_[l], key1_[l],
                   words[i + g][0][l], words[i + g][1][l]);
    }
#endif
    // The fast path right away, while the words are in L1; each normal straight into its lane's slot.
    count += ziggurat_fast(&words[0][0][0], 2 * i, 2 * (i + kGroups), normals, rejects + count);
  }
  slow_normals(rejects, count, [&](int index, Rejected& chunk) {
    const int k = index / kLanes, l = index % kLanes;
    chunk.add(words[k / 2][k % 2][l], first_pair + static_cast<std::uint64_t>(k / 2), k % 2, seed_high_[l], key0_[l],
              key1_[l], normals(k) + l);
  });
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
