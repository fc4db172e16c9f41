// Quantized refinement info must stay conservative: every decoded bound contains the exact one
// (spm/refine_info.h, RefineInfo), and stays tight enough to be useful.
#include <gtest/gtest.h>
#include <cmath>
#include <numbers>
#include <random>

#include "spm/refine_info.h"

namespace pms {
namespace {

constexpr double kPi = std::numbers::pi;
// Precision of the stored info (spm/refine_info.h): lengths keep 6 of the half's 10 mantissa bits, the axis is an
// 11-bit octahedral code (error under 2 of its steps), the cone angle has (pi/2) / 1023 steps.
constexpr double kLengthStep = 0x1p-6;
constexpr double kAxisError = 2.0 / kAxisSteps;
constexpr double kConeStep = kPi / 2 / (kConeSteps + 1);

TEST(HalfFloat, KnownValues) {
  EXPECT_EQ(half_from_float_up(0.0f), 0x0000);
  EXPECT_EQ(half_from_float_up(1.0f), 0x3C00);
  EXPECT_EQ(half_from_float_up(-2.0f), 0x0000) << "negative bounds are treated as 0";
  EXPECT_EQ(half_from_float_up(65504.0f), 0x7BFF) << "the largest finite half is kept";
  EXPECT_EQ(half_from_float_up(65505.0f), 0x7C00) << "anything above it can only be bounded by +inf";
  EXPECT_EQ(half_from_float_up(INFINITY), 0x7C00);
  EXPECT_EQ(half_from_float_up(NAN), 0x7C00) << "an unknown bound must not shrink to 0";
  EXPECT_EQ(half_from_float_up(0x1p-24f), 0x0001);
  EXPECT_EQ(half_from_float_up(1e-30f), 0x0001) << "tiny positive values round up to the smallest subnormal";
  EXPECT_EQ(half_from_float_up(1e-45f), 0x0001) << "float subnormals too";
  EXPECT_EQ(half_from_float_up(0x1p-14f), 0x0400);
  EXPECT_EQ(half_from_float_up(std::nextafter(1.0f, 2.0f)), 0x3C01);
  EXPECT_EQ(float_from_half(0x3C00), 1.0f);
  EXPECT_EQ(float_from_half(0x7BFF), 65504.0f);
  EXPECT_EQ(float_from_half(0x0001), 0x1p-24f);
  EXPECT_EQ(float_from_half(0xC000), -2.0f);
  EXPECT_TRUE(std::isinf(float_from_half(0x7C00)));
  EXPECT_TRUE(std::isnan(float_from_half(0x7E00)));
}

// Every non-negative finite half: exact values encode to themselves, and anything just above the
// previous half rounds up to this one (so the rounding is up, and tight).
TEST(HalfFloat, ExhaustiveOverHalves) {
  float previous = 0;
  for (uint32_t h = 0; h < 0x7C00; ++h) {
    const float v = float_from_half(uint16_t(h));
    ASSERT_EQ(half_from_float_up(v), h) << "half " << h;
    if (h == 0) continue;
    ASSERT_GT(v, previous) << "decoding is monotonic";
    ASSERT_EQ(half_from_float_up(std::nextafter(previous, INFINITY)), h) << "half " << h;
    previous = v;
  }
}

TEST(HalfFloat, RandomValuesDecodeAtLeastAsLarge) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> exponent(-30, 17);
  std::uniform_real_distribution<float> mantissa(1, 2);
  for (int i = 0; i < 200000; ++i) {
    const float v = std::ldexp(mantissa(rng), int(exponent(rng)));
    const uint16_t h = half_from_float_up(v);
    ASSERT_GE(float_from_half(h), v) << v;
    if (h > 0 && h < 0x7C00) {
      ASSERT_LT(float_from_half(uint16_t(h - 1)), v) << "not the smallest half above " << v;
    }
  }
}

double angle(const float a[3], const double b[3]) {
  const double la = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
  const double d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / la;
  const double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2], cz = a[0] * b[1] - a[1] * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz) / la, d);
}

struct Cone {
  double axis[3];
  double angle;
};

// A unit vector at exactly `theta` from unit `axis`, rotated by `phi` around it.
void vector_at_angle(const double axis[3], double theta, double phi, double out[3]) {
  const double helper[3] = {std::abs(axis[0]) < 0.9 ? 1.0 : 0.0, std::abs(axis[0]) < 0.9 ? 0.0 : 1.0, 0};
  double u[3] = {axis[1] * helper[2] - axis[2] * helper[1], axis[2] * helper[0] - axis[0] * helper[2],
                 axis[0] * helper[1] - axis[1] * helper[0]};
  const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (double& c : u) c /= lu;
  const double w[3] = {axis[1] * u[2] - axis[2] * u[1], axis[2] * u[0] - axis[0] * u[2],
                       axis[0] * u[1] - axis[1] * u[0]};
  for (int k = 0; k < 3; ++k)
    out[k] = std::cos(theta) * axis[k] + std::sin(theta) * (std::cos(phi) * u[k] + std::sin(phi) * w[k]);
}

TEST(QuantizeRefine, RandomBoundsDecodeConservativelyAndTightly) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> gauss;
  const float scales[] = {1.0f, 0.001f, 3.7f, 1234.5f, 1e6f};
  for (int i = 0; i < 50000; ++i) {
    const float scale = scales[i % 5];
    RefineBounds b;
    b.radius = float(scale * std::pow(10.0, -6 + 6 * unit(rng)));
    b.mu = float(scale * std::pow(10.0, -7 + 6 * unit(rng)));
    b.delta = i % 7 == 0 ? 0.0f : float(scale * std::pow(10.0, -7 + 6 * unit(rng)));
    double axis[3] = {gauss(rng), gauss(rng), gauss(rng)};
    const double len = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (int k = 0; k < 3; ++k) b.axis[k] = float(axis[k] / len);
    b.cone_angle = float(unit(rng) * 1.6);

    const RefineInfo q = quantize_refine(b, scale);
    ASSERT_TRUE(is_canonical(q));
    const RefineBounds d = dequantize_refine(q, scale);
    ASSERT_GE(d.radius, b.radius);
    ASSERT_GE(d.mu, b.mu);
    ASSERT_GE(d.delta, b.delta);
    // Tight: rounding up plus at most one bump for the float divide/multiply is two stored steps
    // (2^-6 relative each), or two subnormal steps (16 x 2^-24) for tiny values.
    ASSERT_LE(d.radius, b.radius * (1 + 2 * kLengthStep) + 2 * scale * 0x1p-20);
    ASSERT_LE(d.mu, b.mu * (1 + 2 * kLengthStep) + 2 * scale * 0x1p-20);

    const double true_axis[3] = {b.axis[0], b.axis[1], b.axis[2]};
    const double axis_len =
        std::sqrt(double(d.axis[0]) * d.axis[0] + double(d.axis[1]) * d.axis[1] + double(d.axis[2]) * d.axis[2]);
    ASSERT_NEAR(axis_len, 1.0, 1e-6);
    if (b.cone_angle >= kPi / 2) {
      ASSERT_EQ(d.cone_angle, float(kPi)) << "a half-space cone is stored as kNoCone";
      continue;
    }
    const double widening = kAxisError + kConeStep + 1e-6;
    if (d.cone_angle >= kPi / 2) {
      ASSERT_GT(b.cone_angle + widening, kPi / 2) << "only cones already near pi/2 may be widened to no cone";
      continue;
    }
    ASSERT_LT(angle(d.axis, true_axis), kAxisError);
    ASSERT_LE(d.cone_angle, b.cone_angle + widening) << "cone widened by more than axis error + one step";
    // Normals on the rim of the exact cone are inside the decoded one.
    for (int k = 0; k < 8; ++k) {
      double normal[3];
      vector_at_angle(true_axis, b.cone_angle, unit(rng) * 2 * kPi, normal);
      ASSERT_LE(angle(d.axis, normal), d.cone_angle) << "normal outside the decoded cone";
    }
  }
}

TEST(QuantizeRefine, ZeroWidthConeStillContainsItsAxis) {
  for (const float z : {1.0f, -1.0f, 0.0f}) {
    RefineBounds b;
    b.axis[0] = z == 0 ? 0.6f : 0.0f;
    b.axis[1] = z == 0 ? 0.8f : 0.0f;
    b.axis[2] = z;
    b.cone_angle = 0;
    const RefineBounds d = dequantize_refine(quantize_refine(b, 1), 1);
    const double axis[3] = {b.axis[0], b.axis[1], b.axis[2]};
    EXPECT_LE(angle(d.axis, axis), d.cone_angle);
    EXPECT_LT(d.cone_angle, kAxisError + kConeStep + 1e-6);
  }
}

TEST(QuantizeRefine, DegenerateInputsAreConservative) {
  RefineBounds b;
  b.radius = -1;  // treated as 0
  b.mu = NAN;     // unknown: infinite
  b.delta = 1e30f;
  b.axis[0] = b.axis[1] = b.axis[2] = 0;  // no axis: no cone
  b.cone_angle = 0.1f;
  RefineInfo q = quantize_refine(b, 1);
  EXPECT_EQ(q.cone_angle, kNoCone);
  RefineBounds d = dequantize_refine(q, 1);
  EXPECT_EQ(d.radius, 0);
  EXPECT_TRUE(std::isinf(d.mu));
  EXPECT_TRUE(std::isinf(d.delta));
  EXPECT_EQ(d.cone_angle, float(kPi));

  b = RefineBounds{};
  b.cone_angle = NAN;
  EXPECT_EQ(quantize_refine(b, 1).cone_angle, kNoCone);
  b.cone_angle = float(kPi / 2);
  EXPECT_EQ(quantize_refine(b, 1).cone_angle, kNoCone);
  b.cone_angle = float(kPi / 2) - 1e-6f;
  EXPECT_EQ(quantize_refine(b, 1).cone_angle, kNoCone) << "rounded up to pi/2: a half-space";
}

TEST(QuantizeRefine, OnlyQuantizerOutputIsCanonical) {
  RefineBounds b;
  b.radius = 0.3f;
  b.axis[0] = 1;
  b.axis[2] = 0;
  b.cone_angle = 0.2f;
  const RefineInfo good = quantize_refine(b, 1);
  ASSERT_TRUE(is_canonical(good));
  RefineInfo bad = good;
  bad.radius |= 1;  // a dropped mantissa bit
  EXPECT_FALSE(is_canonical(bad));
  bad = good;
  bad.mu = 0x7C10;  // NaN
  EXPECT_FALSE(is_canonical(bad));
  bad = good;
  bad.cone_x = uint16_t(int16_t(-kAxisSteps - 1));
  EXPECT_FALSE(is_canonical(bad));
  bad = good;
  bad.cone_angle = kConeSteps + 1;
  EXPECT_FALSE(is_canonical(bad));
  bad = good;
  bad.cone_angle = kNoCone;  // without a cone the axis must be +z, (0, 0)
  EXPECT_FALSE(is_canonical(bad));
}

TEST(QuantizeRefine, ScaleOfZeroKeepsBoundsUnscaled) {
  RefineBounds b;
  b.radius = 0.3f;
  for (const float scale : {0.0f, -1.0f, NAN}) {
    const RefineBounds d = dequantize_refine(quantize_refine(b, scale), scale);
    EXPECT_GE(d.radius, b.radius);
    EXPECT_LT(d.radius, 0.301f);
  }
}

}  // namespace
}  // namespace pms
