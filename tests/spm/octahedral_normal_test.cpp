// Octahedral normals (spm/octahedral_normal.h): the canonical point of each mirrored pair on the square's
// edges is what decoding and encoding again gives, and steps between normals, across the edges too, fold
// back to the normal they were taken to.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>

#include "spm/octahedral_normal.h"

namespace pms {
namespace {

constexpr int32_t kMax = kOctahedralMax;

uint16_t bits(int32_t v) { return uint16_t(int16_t(v)); }

TEST(OctahedralNormal, EdgePointsAndTheirMirrorImagesAreOneNormalWithOneCanonicalPair) {
  for (int32_t t = -kMax; t <= kMax; ++t) {
    for (const auto& [x, y] : {std::pair{kMax, t}, {-kMax, t}, {t, kMax}, {t, -kMax}}) {
      uint16_t q[2] = {bits(x), bits(y)}, canonical[2] = {q[0], q[1]}, again[2];
      canonical_normal(canonical);
      float n[3], m[3];
      decode_normal(q, n);
      decode_normal(canonical, m);
      for (int k = 0; k < 3; ++k)  // the same up to the decoder's float rounding
        ASSERT_NEAR(n[k], m[k], 1e-6) << x << ", " << y << ": the mirror image is another normal";
      encode_normal(n, again);
      ASSERT_EQ(again[0], canonical[0]) << x << ", " << y;
      ASSERT_EQ(again[1], canonical[1]) << x << ", " << y;
      ASSERT_TRUE(is_canonical_normal(again));
    }
  }
  const uint16_t lowest[2] = {bits(-32768), 0};
  EXPECT_FALSE(is_canonical_normal(lowest)) << "-32768 decodes as -32767";
}

// Normals whose fold lands on an edge once rounded came out as either point of a mirrored pair.
TEST(OctahedralNormal, EncodingIsCanonicalNextToTheEdges) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<float> tiny(-1e-5f, 1e-5f), any(-1, 1);
  for (int trial = 0; trial < 200000; ++trial) {
    // Below the equator near the planes x = 0 or y = 0: the square's edges.
    float n[3] = {any(rng), tiny(rng), -std::abs(any(rng))};
    if (trial % 2) std::swap(n[0], n[1]);
    uint16_t q[2], again[2];
    encode_normal(n, q);
    ASSERT_TRUE(is_canonical_normal(q)) << int16_t(q[0]) << ", " << int16_t(q[1]);
    float back[3];
    decode_normal(q, back);
    encode_normal(back, again);
    ASSERT_EQ(again[0], q[0]);
    ASSERT_EQ(again[1], q[1]);
  }
}

TEST(OctahedralNormal, StepsFoldBackToTheirEndAndCrossEdgesShort) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<float> any(-1, 1), near(-0.02f, 0.02f);
  int crossed = 0;
  for (int trial = 0; trial < 100000; ++trial) {
    float a[3] = {any(rng), any(rng), any(rng)}, b[3];
    for (int k = 0; k < 3; ++k) b[k] = a[k] + near(rng);
    uint16_t from[2], to[2], back[2];
    encode_normal(a, from);
    encode_normal(b, to);
    int64_t d[2];
    octahedral_step(from, to, d);
    ASSERT_TRUE(octahedral_unstep(from, d, back));
    ASSERT_EQ(back[0], to[0]);
    ASSERT_EQ(back[1], to[1]);
    const int64_t direct =
        std::abs(int64_t(int16_t(to[0])) - int16_t(from[0])) + std::abs(int64_t(int16_t(to[1])) - int16_t(from[1]));
    crossed += std::abs(d[0]) + std::abs(d[1]) < direct;
  }
  EXPECT_GT(crossed, 0) << "some nearby normals lie across an edge of the square";
}

TEST(OctahedralNormal, StepsOffTheSquareAndItsCopiesAreRefused) {
  const uint16_t from[2] = {bits(kMax - 10), bits(kMax - 10)};
  uint16_t to[2];
  for (const auto& [dx, dy] :
       {std::pair<int64_t, int64_t>{20, 20}, {3 * kMax, 0}, {0, -4 * kMax}, {int64_t(1) << 40, 0}})
    EXPECT_FALSE(octahedral_unstep(from, std::array<int64_t, 2>{dx, dy}.data(), to)) << dx << ", " << dy;
  EXPECT_TRUE(octahedral_unstep(from, std::array<int64_t, 2>{20, 0}.data(), to));  // over the right edge, mirrored
  EXPECT_EQ(int16_t(to[0]), kMax - 10);
  EXPECT_EQ(int16_t(to[1]), -(kMax - 10));
}

}  // namespace
}  // namespace pms
