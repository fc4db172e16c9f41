// Position quantization: error bounds for every grid width, the box corners exact, clamping, raw float
// bits, idempotence where the grid is coarser than float resolution, and octahedral normals.
#include <gtest/gtest.h>
#include <bit>
#include <cmath>
#include <cstring>

#include "protocol/position_grid.h"
#include "protocol/wire_internal.h"
#include "protocol_fixtures.h"

namespace pms::protocol {
namespace {

PositionGrid grid_of(const float lo[3], const float hi[3], uint32_t bits) {
  PositionGrid grid;
  for (int i = 0; i < 3; ++i) {
    grid.min[i] = lo[i];
    grid.max[i] = hi[i];
  }
  grid.bits = bits;
  return grid;
}

TEST(Quantize, ValidBits) {
  EXPECT_FALSE(valid_position_bits(0));
  for (uint32_t bits = 1; bits <= 24; ++bits) {
    EXPECT_TRUE(valid_position_bits(bits));
  }
  for (uint32_t bits = 25; bits < 32; ++bits) {
    EXPECT_FALSE(valid_position_bits(bits));
  }
  EXPECT_TRUE(valid_position_bits(32));
  EXPECT_FALSE(valid_position_bits(33));
}

TEST(Quantize, ErrorWithinHalfAStep) {
  const float lo[3] = {-0.094f, 0.033f, -0.062f}, hi[3] = {0.061f, 0.187f, 0.059f};  // the bunny's box
  for (uint32_t bits = 1; bits <= 24; ++bits) {
    const PositionGrid grid = grid_of(lo, hi, bits);
    test::Rng rng(bits);
    for (int trial = 0; trial < 2000; ++trial) {
      float p[3], back[3];
      for (int i = 0; i < 3; ++i) p[i] = test::random_float(rng, lo[i], hi[i]);
      uint32_t q[3];
      quantize_position(grid, p, q);
      for (uint32_t v : q) {
        ASSERT_LE(v, (uint64_t(1) << bits) - 1);
      }
      dequantize_position(grid, q, back);
      for (int i = 0; i < 3; ++i) {
        const double step = (double(hi[i]) - lo[i]) / double((uint64_t(1) << bits) - 1);
        ASSERT_LE(std::abs(double(back[i]) - p[i]), position_error_bound(grid, i)) << bits << " bits";
        ASSERT_LE(position_error_bound(grid, i), step / 2 * 1.001 + 2e-8) << "the bound is about half a step";
        ASSERT_GE(back[i], lo[i]);
        ASSERT_LE(back[i], hi[i]);
      }
    }
  }
}

TEST(Quantize, CornersExactAndOutsideClamped) {
  const float lo[3] = {-3, 0.25f, 10}, hi[3] = {5, 0.75f, 1000};
  for (uint32_t bits : {1u, 8u, 16u, 24u}) {
    const PositionGrid grid = grid_of(lo, hi, bits);
    float p[3];
    snap_position(grid, lo, p);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(p[i], lo[i]);
    }
    snap_position(grid, hi, p);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(p[i], hi[i]);
    }
    const float outside[3] = {-100, 7, NAN};
    snap_position(grid, outside, p);
    EXPECT_EQ(p[0], lo[0]);
    EXPECT_EQ(p[1], hi[1]);
    EXPECT_EQ(p[2], lo[2]);  // NaN lands on the minimum
  }
}

TEST(Quantize, FlatAxisDecodesToItsValue) {
  // A planar grid: z extent 0 (the builder's bbox of make_grid).
  const float lo[3] = {0, 0, 0.5f}, hi[3] = {1, 1, 0.5f};
  const PositionGrid grid = grid_of(lo, hi, 16);
  const float p[3] = {0.3f, 0.7f, 0.5f};
  float back[3];
  snap_position(grid, p, back);
  EXPECT_EQ(back[2], 0.5f);
  EXPECT_EQ(position_error_bound(grid, 2), 0.0f);
}

TEST(Quantize, RawFloatBits) {
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const PositionGrid grid = grid_of(lo, hi, 32);
  const float p[3] = {-1e30f, 0.1f, std::nextafter(1.0f, 2.0f)};  // outside the box: raw bits are not clamped
  uint32_t q[3];
  quantize_position(grid, p, q);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(q[i], std::bit_cast<uint32_t>(p[i]));
  }
  float back[3];
  dequantize_position(grid, q, back);
  EXPECT_EQ(std::memcmp(back, p, sizeof p), 0);
  EXPECT_EQ(position_error_bound(grid, 0), 0.0f);
}

TEST(Quantize, IdempotentWhenTheGridIsCoarserThanFloats) {
  // max|coord| / extent < 2^(23 - bits): re-quantizing a dequantized position gives the same integer, so
  // a server that keeps dequantized positions and re-encodes them sends the same bytes.
  const float lo[3] = {-1, -2, 0}, hi[3] = {1, 3, 0.5f};
  for (uint32_t bits : {1u, 8u, 12u, 16u, 20u}) {
    const PositionGrid grid = grid_of(lo, hi, bits);
    test::Rng rng(bits);
    for (int trial = 0; trial < 5000; ++trial) {
      uint32_t q[3], again[3];
      for (uint32_t& v : q) v = uint32_t(rng() & ((uint64_t(1) << bits) - 1));
      float p[3];
      dequantize_position(grid, q, p);
      quantize_position(grid, p, again);
      for (int i = 0; i < 3; ++i) ASSERT_EQ(again[i], q[i]) << bits << " bits, axis " << i;
    }
  }
}

TEST(Quantize, NormalsOctahedral) {
  test::Rng rng(3);
  for (int trial = 0; trial < 20000; ++trial) {
    float n[3], length = 0;
    for (float& v : n) {
      v = test::random_float(rng, -1, 1);
      length += v * v;
    }
    if (length < 1e-6f) continue;
    for (float& v : n) v /= std::sqrt(length);
    uint16_t q[2], again[2];
    encode_normal(n, q);
    float back[3];
    decode_normal(q, back);
    double back_length = 0;
    for (int i = 0; i < 3; ++i) back_length += double(back[i]) * back[i];
    ASSERT_NEAR(back_length, 1.0, 1e-6);
    ASSERT_LT(test::angle_between(n, back), 1e-4) << "normal error over 1e-4 rad";
    encode_normal(back, again);  // decoded normals re-encode to themselves
    ASSERT_EQ(again[0], q[0]);
    ASSERT_EQ(again[1], q[1]);
  }
  // Axes, the fold's edges, and no direction at all.
  const float axes[][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 0}};
  for (const auto& a : axes) {
    uint16_t q[2];
    encode_normal(a, q);
    float back[3];
    decode_normal(q, back);
    if (a[0] == 0 && a[1] == 0 && a[2] == 0) {
      EXPECT_EQ(back[2], 1.0f);
      continue;
    }
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(back[i], a[i], 1e-6);
    }
  }
}

}  // namespace
}  // namespace pms::protocol
