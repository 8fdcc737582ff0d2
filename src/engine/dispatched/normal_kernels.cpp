// The normal generator's SIMD parts (engine/normal_stream.hpp), compiled once per instruction set:
// each variant includes the generator header its instruction set has (src/engine/normal/), which
// give the same numbers bit for bit.
#include "variant.hpp"

#include <boost/random/normal_distribution.hpp>

#include <algorithm>

#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
#include "../normal/avx512.hpp"
#elif defined(__AVX2__)
#include "../normal/avx2.hpp"
#else
#include "../normal/scalar.hpp"
#endif

namespace gear_dynamics::GD_ISA_NAMESPACE {


namespace {

using namespace normals;

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

// The slow path for the rejects of ziggurat_fast (add(index, chunk) puts each into a chunk),
// kChunk at a time so that their first retry words come from one SIMD Philox: Boost's wedge test
// in SIMD (simd_wedge, where the variant has it), and Boost.Random's normal_distribution<double>(0, 1)
// in full on the engine of each normal it does not decide (it repeats the first test on the main
// word and goes on to the wedge or the tail).
template <class Add>
void slow_normals(const std::uint16_t* rejects, int count, Add add) {
  for (int start = 0; start < count; start += Rejected::kChunk) {
    Rejected chunk{};  // zeros past its count, where the SIMD wedge reads whole vectors
    for (int n = start; n < std::min(count, start + Rejected::kChunk); ++n) add(rejects[n], chunk);
    first_retry_words(chunk);
    std::uint32_t undecided = (1u << chunk.count) - 1;
    if constexpr (kSimdWedge) {
      double value[Rejected::kChunk];
      const std::uint32_t decided = simd_wedge(chunk, value);
      for (int i = 0; i < chunk.count; ++i) *chunk.out[i] = value[i];  // the undecided are overwritten below
      undecided &= ~decided;
    }
    for (; undecided != 0; undecided &= undecided - 1) {
      const int i = __builtin_ctz(undecided);
      ReplayEngine engine(chunk, i);
      *chunk.out[i] = boost::random::normal_distribution<double>(0.0, 1.0)(engine);
    }
  }
}

}  // namespace

void philox(const dispatch::StreamKey& key, std::uint64_t first_pair, std::uint64_t* w0, std::uint64_t* w1) {
  // Philox4x32-10 on the counters (p, p >> 32, seed_high, 0) for kBlockPairs consecutive p, run
  // side by side. Random123's implementation works one counter at a time and compilers turn its
  // 32 x 32 -> 64 bit products into slow 64-bit vector multiplies, hence the variant's Words (a
  // vector with AVX-512 or AVX2, one word without); all are integer arithmetic, so they agree bit
  // for bit (test_random checks them against r123::Philox4x32).
  int i = 0;
  // kGroups vectors of counters advance together: the rounds are a latency chain, and
  // independent chains side by side keep the multipliers busy.
  constexpr int kGroups = 4, kWidth = kWordsPerVector;
  for (; i + kWidth * kGroups <= kBlockPairs; i += kWidth * kGroups) {
    Words c0[kGroups], c1[kGroups], c2[kGroups], c3[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      c0[g] = words_iota(first_pair + static_cast<std::uint64_t>(i + kWidth * g));
      c1[g] = high_to_low(c0[g]);
      c2[g] = words_set1(key.seed_high);
      c3[g] = words_set1(0);
    }
    std::uint32_t k0 = key.key0, k1 = key.key1;
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
  for (; i < kBlockPairs; ++i)
    philox_one(first_pair + static_cast<std::uint64_t>(i), key.seed_high, 0u, key.key0, key.key1, w0[i], w1[i]);
}

void normal_block(const dispatch::StreamKey& key, std::uint64_t first_pair, double* out) {
  // words[j][i]: word j of counter first_pair + i, i.e. the main word of normal 2 (first_pair + i) + j.
  alignas(64) std::uint64_t words[2][kBlockPairs];
  philox(key, first_pair, words[0], words[1]);
  alignas(64) double normals[2][kBlockPairs];
  constexpr int kVectors = 2 * kBlockPairs / 8;
  static_assert(kVectors <= 8, "ziggurat_fast takes up to 8 vectors at a time");
  std::uint16_t rejects[2 * kBlockPairs + kRejectsSlack];
  const int count = ziggurat_fast(&words[0][0], 0, kVectors, [&](int v) { return &normals[0][0] + 8 * v; }, rejects);
  slow_normals(rejects, count, [&](int index, Rejected& chunk) {
    const int j = index / kBlockPairs, i = index % kBlockPairs;
    chunk.add(words[j][i], first_pair + static_cast<std::uint64_t>(i), j, key.seed_high, key.key0, key.key1, &normals[j][i]);
  });
  for (int i = 0; i < kBlockPairs; ++i) {
    out[2 * i] = normals[0][i];
    out[2 * i + 1] = normals[1][i];
  }
}

void normal_lanes_block(const dispatch::LaneKeys& keys, std::uint64_t first_pair, double* out, std::ptrdiff_t stride) {
  constexpr int kLanes = NormalLanes::kLanes;
  static_assert(kLanes == 8, "dispatch::LaneKeys holds 8 lanes");
  // kGroups counters at a time, each in kLanes / kWordsPerVector vectors: at least four independent
  // Philox chains side by side.
  constexpr int kVectors = kLanes / kWordsPerVector, kGroups = std::max(1, 4 / kVectors);
  static_assert(kBlockPairs % kGroups == 0 && 2 * kGroups <= 8);  // ziggurat_fast: up to 8 vectors at a time
  // words[i][j][l]: word j of counter first_pair + i of lane l, the main word of the lane's normal
  // k = 2 (first_pair + i) + j, which goes to out[k * stride + l]; vector k of 8 words.
  alignas(64) std::uint64_t words[kBlockPairs][2][kLanes];
  std::uint16_t rejects[2 * kBlockPairs * kLanes + kRejectsSlack];
  int count = 0;
  const auto normals = [&](int k) { return out + k * stride; };
  for (int i = 0; i < kBlockPairs; i += kGroups) {
    // NormalStream::philox with the counter the same in every lane and the keys per lane.
    Words c0[kGroups][kVectors], c1[kGroups][kVectors], c2[kGroups][kVectors], c3[kGroups][kVectors];
    for (int g = 0; g < kGroups; ++g) {
      const std::uint64_t p = first_pair + static_cast<std::uint64_t>(i + g);
      for (int v = 0; v < kVectors; ++v) {
        c0[g][v] = words_set1(p & kLow);
        c1[g][v] = words_set1(p >> 32);
        c2[g][v] = words_from_u32(keys.seed_high + kWordsPerVector * v);
        c3[g][v] = words_set1(0);
      }
    }
    for (int round = 0; round < 10; ++round) {
      for (int v = 0; v < kVectors; ++v) {
        const Words key0 = words_load(keys.round_keys[round][0] + kWordsPerVector * v);
        const Words key1 = words_load(keys.round_keys[round][1] + kWordsPerVector * v);
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
    // The fast path right away, while the words are in L1; each normal straight into its lane's slot.
    count += ziggurat_fast(&words[0][0][0], 2 * i, 2 * (i + kGroups), normals, rejects + count);
  }
  slow_normals(rejects, count, [&](int index, Rejected& chunk) {
    const int k = index / kLanes, l = index % kLanes;
    chunk.add(words[k / 2][k % 2][l], first_pair + static_cast<std::uint64_t>(k / 2), k % 2, keys.seed_high[l], keys.key0[l],
              keys.key1[l], normals(k) + l);
  });
}

}  // namespace gear_dynamics::GD_ISA_NAMESPACE
