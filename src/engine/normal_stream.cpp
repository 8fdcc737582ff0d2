#include "gear_dynamics/engine/normal_stream.hpp"

#include <Eigen/Core>
#include <immintrin.h>
#include <algorithm>
#include <array>
#include <cmath>

namespace gear_dynamics {

namespace {

constexpr int kBlockPairs = NormalStream::kBlockPairs;
constexpr double kQuarterPi = 0.78539816339744830962;
// Taylor coefficients of sin(t) / t and cos(t) in t^2, highest first; on |t| <= pi/4 the first
// omitted terms are below 5e-17.
constexpr std::array<double, 8> kSinTaylor = {-1.0 / 1307674368000, 1.0 / 6227020800, -1.0 / 39916800,
                                              1.0 / 362880, -1.0 / 5040, 1.0 / 120, -1.0 / 6, 1.0};
constexpr std::array<double, 9> kCosTaylor = {1.0 / 20922789888000, -1.0 / 87178291200, 1.0 / 479001600,
                                              -1.0 / 3628800, 1.0 / 40320, -1.0 / 720, 1.0 / 24, -0.5, 1.0};

// Philox4x32-10 (Salmon et al. 2011) constants, as in Random123's philox.h.
constexpr std::uint32_t kPhiloxM0 = 0xD2511F53u, kPhiloxM1 = 0xCD9E8D57u;
constexpr std::uint32_t kPhiloxW0 = 0x9E3779B9u, kPhiloxW1 = 0xBB67AE85u;
constexpr std::uint64_t kLow = 0xFFFFFFFFull;  // a 32-bit word held in 64 bits

// Philox4x32-10 of one counter (p, p >> 32, seed_high, 0) with key (k0, k1), as the words
// w0 = out[1]:out[0] and w1 = out[3]:out[2]: the reference the SIMD paths must equal.
inline void philox_one(std::uint64_t p, std::uint32_t seed_high, std::uint32_t k0, std::uint32_t k1,
                       std::uint64_t& w0, std::uint64_t& w1) {
  std::uint64_t c0 = p & kLow, c1 = p >> 32, c2 = seed_high, c3 = 0u;
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
  // 32 x 32 -> 64 bit products into slow 64-bit vector multiplies, hence the AVX-512 path;
  // both paths are integer arithmetic, so they agree bit for bit (test_random checks both
  // against r123::Philox4x32).
  int i = 0;
#ifdef __AVX512F__
  // kGroups vectors of 8 counters advance together: the rounds are a latency chain, and
  // independent chains side by side keep the multipliers busy.
  constexpr int kGroups = 4;
  const __m512i low = _mm512_set1_epi64(static_cast<long long>(kLow));
  const __m512i m0 = _mm512_set1_epi64(kPhiloxM0), m1 = _mm512_set1_epi64(kPhiloxM1);
  const __m512i lane = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0);
  for (; i + 8 * kGroups <= kBlockPairs; i += 8 * kGroups) {
    __m512i c0[kGroups], c1[kGroups], c2[kGroups], c3[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      const __m512i p = _mm512_add_epi64(_mm512_set1_epi64(static_cast<long long>(first_pair + i + 8 * g)), lane);
      c0[g] = _mm512_and_si512(p, low);
      c1[g] = _mm512_srli_epi64(p, 32);
      c2[g] = _mm512_set1_epi64(seed_high_);
      c3[g] = _mm512_setzero_si512();
    }
    std::uint32_t k0 = key_[0], k1 = key_[1];
    for (int round = 0; round < 10; ++round) {
      const __m512i key0 = _mm512_set1_epi64(k0), key1 = _mm512_set1_epi64(k1);
      for (int g = 0; g < kGroups; ++g) {
        const __m512i p0 = _mm512_mul_epu32(c0[g], m0);  // low 32 bits of each lane, 64-bit product
        const __m512i p1 = _mm512_mul_epu32(c2[g], m1);
        c0[g] = _mm512_xor_si512(_mm512_xor_si512(_mm512_srli_epi64(p1, 32), c1[g]), key0);
        c1[g] = _mm512_and_si512(p1, low);
        c2[g] = _mm512_xor_si512(_mm512_xor_si512(_mm512_srli_epi64(p0, 32), c3[g]), key1);
        c3[g] = _mm512_and_si512(p0, low);
      }
      k0 += kPhiloxW0;
      k1 += kPhiloxW1;
    }
    for (int g = 0; g < kGroups; ++g) {
      _mm512_storeu_si512(w0 + i + 8 * g, _mm512_or_si512(_mm512_slli_epi64(c1[g], 32), c0[g]));
      _mm512_storeu_si512(w1 + i + 8 * g, _mm512_or_si512(_mm512_slli_epi64(c3[g], 32), c2[g]));
    }
  }
#endif
  for (; i < kBlockPairs; ++i)
    philox_one(first_pair + static_cast<std::uint64_t>(i), seed_high_, key_[0], key_[1], w0[i], w1[i]);
}

namespace {

// Box-Muller on the two 64-bit words of each counter: radius sqrt(-2 ln u) from w1, and the
// angle from w0 as phi uniform in (-pi/4, pi/4) (52 bits) turned by one of four quarter turns
// (2 bits: swap sin/cos, negate both), which is uniform on the circle without a range reduction.
// sin and cos of |phi| <= pi/4 are Taylor polynomials. The log is Eigen's SIMD log, always on
// whole packets of 8, so a normal's value depends only on its counter, never on how a caller
// chunks its requests or which lane it sits in. N pairs at once (a multiple of 8): each statement
// is N / 8 independent vector chains side by side, which hides their latency. Pair i's normals go
// to first[i] and second[i].
template <int N>
void box_muller(const std::uint64_t* w0, const std::uint64_t* w1, double* first, double* second) {
  static_assert(N % 8 == 0);
  using Block = Eigen::Array<double, N, 1>;
  constexpr std::uint64_t kAngleBits = 0xFFFFFFFFFFFFFull;
  Block angle_bits, radius_bits;  // exact conversions: both < 2^53
#ifdef __AVX512DQ__
  for (int i = 0; i < N; i += 8) {  // GCC converts one word at a time otherwise
    const __m512i a = _mm512_loadu_si512(w0 + i), r = _mm512_loadu_si512(w1 + i);
    _mm512_storeu_pd(angle_bits.data() + i,
                     _mm512_cvtepu64_pd(_mm512_and_si512(a, _mm512_set1_epi64(static_cast<long long>(kAngleBits)))));
    _mm512_storeu_pd(radius_bits.data() + i, _mm512_cvtepu64_pd(_mm512_srli_epi64(r, 11)));
  }
#else
  for (int i = 0; i < N; ++i) {
    angle_bits[i] = static_cast<double>(w0[i] & kAngleBits);
    radius_bits[i] = static_cast<double>(w1[i] >> 11);
  }
#endif
  const Block uniform = (radius_bits + 0.5) * 0x1p-53;  // (0, 1)
  const Block phi = ((angle_bits + 0.5) * 0x1p-52 - 0.5) * 2.0 * kQuarterPi;
  const Block log_u = uniform.log();  // a statement of its own: Eigen's SIMD path needs it alone
  const Block t2 = phi * phi;
  Block sin_poly = Block::Constant(kSinTaylor[0]), cos_poly = Block::Constant(kCosTaylor[0]);
  for (std::size_t k = 1; k < kSinTaylor.size(); ++k) sin_poly = sin_poly * t2 + kSinTaylor[k];
  for (std::size_t k = 1; k < kCosTaylor.size(); ++k) cos_poly = cos_poly * t2 + kCosTaylor[k];
  const Block s = phi * sin_poly;
  const Block radius_squared = -2.0 * log_u;
#ifdef __AVX512F__
  for (int i = 0; i < N; i += 8) {  // sqrt and the quarter turn in vectors (Eigen's sqrt and GCC keep the loop below scalar)
    const __m512i bits = _mm512_loadu_si512(w0 + i);
    const __mmask8 swap = _mm512_test_epi64_mask(bits, _mm512_set1_epi64(static_cast<long long>(1ull << 63)));
    const __mmask8 negate = _mm512_test_epi64_mask(bits, _mm512_set1_epi64(1ll << 62));
    const __m512d r = _mm512_sqrt_pd(_mm512_loadu_pd(radius_squared.data() + i));  // correctly rounded
    const __m512d signed_r = _mm512_mask_mul_pd(r, negate, r, _mm512_set1_pd(-1.0));
    const __m512d sin_v = _mm512_loadu_pd(s.data() + i), cos_v = _mm512_loadu_pd(cos_poly.data() + i);
    _mm512_storeu_pd(first + i, _mm512_mul_pd(_mm512_mask_blend_pd(swap, sin_v, cos_v), signed_r));
    _mm512_storeu_pd(second + i, _mm512_mul_pd(_mm512_mask_blend_pd(swap, cos_v, sin_v), signed_r));
  }
#else
  for (int i = 0; i < N; ++i) {
    const bool swap = (w0[i] >> 63) != 0;
    const double r = std::sqrt(radius_squared[i]) * ((w0[i] >> 62 & 1u) ? -1.0 : 1.0);
    first[i] = (swap ? cos_poly[i] : s[i]) * r;
    second[i] = (swap ? s[i] : cos_poly[i]) * r;
  }
#endif
}

}  // namespace

void NormalStream::block(std::uint64_t first_pair, double* out) const {
  alignas(64) std::uint64_t w0[kBlockPairs], w1[kBlockPairs];
  philox(first_pair, w0, w1);
  double first[kBlockPairs], second[kBlockPairs];
  box_muller<kBlockPairs>(w0, w1, first, second);
  for (int i = 0; i < kBlockPairs; ++i) {
    out[2 * i] = first[i];
    out[2 * i + 1] = second[i];
  }
}

NormalLanes::NormalLanes(std::uint64_t seed, const std::uint64_t (&realizations)[kLanes]) {
  for (int l = 0; l < kLanes; ++l) {
    const NormalStream stream(seed, realizations[l]);
    key0_[l] = stream.key_[0];
    key1_[l] = stream.key_[1];
    seed_high_[l] = stream.seed_high_;
  }
}

void NormalLanes::block(std::uint64_t first_pair, double* out, std::ptrdiff_t stride) const {
  // kGroups counters at a time: independent Philox and Box-Muller chains side by side.
  constexpr int kGroups = 4;
  static_assert(kBlockPairs % kGroups == 0);
  for (int i = 0; i < kBlockPairs; i += kGroups) {
    alignas(64) std::uint64_t w0[kGroups][kLanes], w1[kGroups][kLanes];
#ifdef __AVX512F__
    // NormalStream::philox with the counter the same in every lane and the keys per lane.
    const __m512i low = _mm512_set1_epi64(static_cast<long long>(kLow));
    const __m512i m0 = _mm512_set1_epi64(kPhiloxM0), m1 = _mm512_set1_epi64(kPhiloxM1);
    __m512i c0[kGroups], c1[kGroups], c2[kGroups], c3[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      const std::uint64_t p = first_pair + static_cast<std::uint64_t>(i + g);
      c0[g] = _mm512_set1_epi64(static_cast<long long>(p & kLow));
      c1[g] = _mm512_set1_epi64(static_cast<long long>(p >> 32));
      c2[g] = _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(seed_high_)));
      c3[g] = _mm512_setzero_si512();
    }
    // 32-bit key words in 64-bit lanes; the 32-bit adds wrap as uint32_t does.
    __m512i key0 = _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(key0_)));
    __m512i key1 = _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(key1_)));
    const __m512i w0_step = _mm512_set1_epi64(kPhiloxW0), w1_step = _mm512_set1_epi64(kPhiloxW1);
    // Only the low 32 bits of each word are the state: vpmuludq reads nothing else, so the high
    // halves may carry junk through the rounds and are cleared once at the end.
    for (int round = 0; round < 10; ++round) {
      for (int g = 0; g < kGroups; ++g) {
        const __m512i p0 = _mm512_mul_epu32(c0[g], m0);
        const __m512i p1 = _mm512_mul_epu32(c2[g], m1);
        c0[g] = _mm512_xor_si512(_mm512_xor_si512(_mm512_srli_epi64(p1, 32), c1[g]), key0);
        c1[g] = p1;
        c2[g] = _mm512_xor_si512(_mm512_xor_si512(_mm512_srli_epi64(p0, 32), c3[g]), key1);
        c3[g] = p0;
      }
      key0 = _mm512_add_epi32(key0, w0_step);  // the high halves stay 0
      key1 = _mm512_add_epi32(key1, w1_step);
    }
    for (int g = 0; g < kGroups; ++g) {
      _mm512_store_si512(w0[g], _mm512_or_si512(_mm512_slli_epi64(c1[g], 32), _mm512_and_si512(c0[g], low)));
      _mm512_store_si512(w1[g], _mm512_or_si512(_mm512_slli_epi64(c3[g], 32), _mm512_and_si512(c2[g], low)));
    }
#else
    for (int g = 0; g < kGroups; ++g) {
      for (int l = 0; l < kLanes; ++l)
        philox_one(first_pair + static_cast<std::uint64_t>(i + g), seed_high_[l], key0_[l], key1_[l], w0[g][l],
                   w1[g][l]);
    }
#endif
    alignas(64) double first[kGroups][kLanes], second[kGroups][kLanes];
    box_muller<kGroups * kLanes>(&w0[0][0], &w1[0][0], &first[0][0], &second[0][0]);
    for (int g = 0; g < kGroups; ++g) {
      const std::ptrdiff_t k = 2 * (i + g);
      std::copy(first[g], first[g] + kLanes, out + k * stride);
      std::copy(second[g], second[g] + kLanes, out + (k + 1) * stride);
    }
  }
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
