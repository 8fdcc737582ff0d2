// Philox4x32-10's round and output on the variant's Words (a vector of 64-bit lanes, or one
// 64-bit word for the scalar variant), one 32-bit word of the state in the low half of each lane.
// vpmuludq reads only the low halves, so the high halves may carry junk through the rounds;
// philox_words clears them. A product's high half moves down by swapping the dwords of each lane
// (vpshufd, a shuffle) rather than by a shift, which would compete with the multiplies for the port
// that runs both on 512-bit vectors. Included by each variant header after its Words operations.
#pragma once

namespace gear_dynamics::normals {

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

}  // namespace gear_dynamics::normals
