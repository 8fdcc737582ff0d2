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

// The 64-bit engine Boost.Random's normal_distribution draws normal k = 2p + j of a stream from:
// first the main word (word j of counter (p, p >> 32, seed_high, 0)), then, should the ziggurat
// reject or fall into the tail, the words of the retry counters (p, p >> 32, seed_high, 1 + j + 2m)
// for m = 0, 1, ..., each giving w0 then w1. The retry words are computed only when asked for.
class ReplayEngine {
 public:
  using result_type = std::uint64_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }

  ReplayEngine(std::uint64_t main_word, std::uint64_t p, int j, std::uint32_t seed_high, std::uint32_t k0,
               std::uint32_t k1)
      : main_word_(main_word), p_(p), seed_high_(seed_high), k0_(k0), k1_(k1), next_c3_(1u + static_cast<unsigned>(j)) {}

  result_type operator()() {
    if (drawn_ == 0) {
      drawn_ = 1;
      return main_word_;
    }
    if (drawn_ % 2 == 1) {
      philox_one(p_, seed_high_, next_c3_, k0_, k1_, retry_[0], retry_[1]);
      next_c3_ += 2;
    }
    return retry_[(drawn_++ - 1) % 2];
  }

 private:
  std::uint64_t main_word_, p_;
  std::uint32_t seed_high_, k0_, k1_, next_c3_;
  std::uint64_t retry_[2] = {0, 0};
  unsigned drawn_ = 0;
};

// Normal 2p + j of the stream with key (k0, k1) and seed_high whose main word is `word`: the slow
// path, Boost.Random's ziggurat in full (it repeats the fast test on `word` and goes on from there).
double boost_normal(std::uint64_t word, std::uint64_t p, int j, std::uint32_t seed_high, std::uint32_t k0,
                    std::uint32_t k1) {
  ReplayEngine engine(word, p, j, seed_high, k0, k1);
  return boost::random::normal_distribution<double>(0.0, 1.0)(engine);
}

// The fast path of Boost.Random's 128-layer ziggurat (normal_distribution.hpp, int_float_pair.hpp)
// on the 8 words w[0..7], with Boost's own table: one 64-bit word gives the sign (bit 0), the layer
// i (bits 1-7) and the uniform r = ((w with bit 11 cleared) >> 8) 2^-56 in [0, 1); x = r x_i is
// accepted if x < x_{i+1}, about 98.8 % of the time. The value returned is Boost's
// (x sign) 1 + 0, i.e. x or 0 - x (so -0 becomes +0). Writes the accepted lanes' normals to out and
// returns the mask of the lanes it could not accept: those need boost_normal. Integer operations,
// an exact conversion of a 56-bit integer rounded to nearest and two multiplications, so the SIMD
// and the plain loop agree bit for bit.
inline unsigned ziggurat_fast8(const std::uint64_t* w, double* out) {
  const double* const table_x = boost::random::detail::normal_table<double>::table_x;
  constexpr std::uint64_t kClearBit11 = ~(std::uint64_t{1} << 11);
#ifdef __AVX512DQ__
  const __m512i u = _mm512_loadu_si512(w);
  const __m512i layer = _mm512_and_si512(_mm512_srli_epi64(u, 1), _mm512_set1_epi64(0x7F));
  const __m512i bits = _mm512_srli_epi64(_mm512_and_si512(u, _mm512_set1_epi64(static_cast<long long>(kClearBit11))), 8);
  const __m512d r = _mm512_mul_pd(_mm512_cvtepu64_pd(bits), _mm512_set1_pd(0x1p-56));
  const __m512d x_i = _mm512_i64gather_pd(layer, table_x, 8);
  const __m512d x_next = _mm512_i64gather_pd(layer, table_x + 1, 8);
  const __m512d x = _mm512_mul_pd(r, x_i);
  const __mmask8 accepted = _mm512_cmp_pd_mask(x, x_next, _CMP_LT_OQ);
  const __mmask8 negative = _mm512_testn_epi64_mask(u, _mm512_set1_epi64(1));
  _mm512_mask_storeu_pd(out, accepted, _mm512_mask_sub_pd(x, negative, _mm512_setzero_pd(), x));
  return static_cast<unsigned>(static_cast<__mmask8>(~accepted));
#else
  unsigned rejected = 0;
  for (int l = 0; l < 8; ++l) {
    const int layer = static_cast<int>(w[l] >> 1 & 0x7F);
    const double r = static_cast<double>((w[l] & kClearBit11) >> 8) * 0x1p-56;
    const double x = r * table_x[layer];
    if (x < table_x[layer + 1])
      out[l] = (w[l] & 1) ? x : 0.0 - x;
    else
      rejected |= 1u << l;
  }
  return rejected;
#endif
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
    philox_one(first_pair + static_cast<std::uint64_t>(i), seed_high_, 0u, key_[0], key_[1], w0[i], w1[i]);
}

void NormalStream::block(std::uint64_t first_pair, double* out) const {
  alignas(64) std::uint64_t w0[kBlockPairs], w1[kBlockPairs];
  philox(first_pair, w0, w1);
  alignas(64) double first[kBlockPairs], second[kBlockPairs];
  for (int i = 0; i < kBlockPairs; i += 8) {
    for (int j = 0; j < 2; ++j) {
      const std::uint64_t* words = j == 0 ? w0 + i : w1 + i;
      double* normals = j == 0 ? first + i : second + i;
      for (unsigned rejected = ziggurat_fast8(words, normals); rejected != 0; rejected &= rejected - 1) {
        const int l = __builtin_ctz(rejected);
        normals[l] = boost_normal(words[l], first_pair + static_cast<std::uint64_t>(i + l), j, seed_high_, key_[0],
                                  key_[1]);
      }
    }
  }
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
  // kGroups counters at a time: independent Philox chains side by side.
  constexpr int kGroups = 4;
  static_assert(kBlockPairs % kGroups == 0);
  for (int i = 0; i < kBlockPairs; i += kGroups) {
    alignas(64) std::uint64_t w[kGroups][2][kLanes];  // word j of counter first_pair + i + g, lane by lane
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
      _mm512_store_si512(w[g][0], _mm512_or_si512(_mm512_slli_epi64(c1[g], 32), _mm512_and_si512(c0[g], low)));
      _mm512_store_si512(w[g][1], _mm512_or_si512(_mm512_slli_epi64(c3[g], 32), _mm512_and_si512(c2[g], low)));
    }
#else
    for (int g = 0; g < kGroups; ++g) {
      for (int l = 0; l < kLanes; ++l)
        philox_one(first_pair + static_cast<std::uint64_t>(i + g), seed_high_[l], 0u, key0_[l], key1_[l], w[g][0][l],
                   w[g][1][l]);
    }
#endif
    // Normal 2p + j of every lane, straight into its lane's slot.
    for (int g = 0; g < kGroups; ++g) {
      const std::uint64_t p = first_pair + static_cast<std::uint64_t>(i + g);
      for (int j = 0; j < 2; ++j) {
        double* normals = out + static_cast<std::ptrdiff_t>(2 * (i + g) + j) * stride;
        for (unsigned rejected = ziggurat_fast8(w[g][j], normals); rejected != 0; rejected &= rejected - 1) {
          const int l = __builtin_ctz(rejected);
          normals[l] = boost_normal(w[g][j][l], p, j, seed_high_[l], key0_[l], key1_[l]);
        }
      }
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
