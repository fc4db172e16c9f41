// portable_sin / cos / tan: within an ulp of the exact value (libm's in double, rounded once) over the
// ranges the view math uses and beyond, and C's special cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>

#include "common/portable_math.h"

namespace pms {
namespace {

// Distance in representable floats (same sign assumed, as every compared pair here has).
int64_t ulps(float a, float b) {
  int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  if (ia < 0) ia = std::numeric_limits<int32_t>::min() - ia;
  if (ib < 0) ib = std::numeric_limits<int32_t>::min() - ib;
  return std::abs(int64_t(ia) - int64_t(ib));
}

template <class Portable, class Exact>
void expect_within_an_ulp(float lo, float hi, Portable portable, Exact exact, const char* what) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> pick(lo, hi);
  int64_t worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const float x = pick(rng);
    const float want = float(exact(double(x)));
    worst = std::max(worst, ulps(portable(x), want));
  }
  EXPECT_LE(worst, 1) << what << " over [" << lo << ", " << hi << "]";
}

double exact_sin(double x) { return std::sin(x); }
double exact_cos(double x) { return std::cos(x); }
double exact_tan(double x) { return std::tan(x); }

TEST(PortableMath, WithinAnUlpWhereTheViewMathUsesIt) {
  constexpr float half_pi = std::numbers::pi_v<float> / 2;
  // make_view: tan of half the vertical field of view, in (0, pi/2).
  expect_within_an_ulp(1e-4f, half_pi - 1e-3f, portable_tan, exact_tan, "tan");
  // node_criteria: the cone's half-angle, in [0, pi/2).
  expect_within_an_ulp(0, half_pi, portable_cos, exact_cos, "cos");
  expect_within_an_ulp(0, half_pi, portable_sin, exact_sin, "sin");
}

TEST(PortableMath, WithinAnUlpOverSeveralTurns) {
  expect_within_an_ulp(-100, 100, portable_sin, exact_sin, "sin");
  expect_within_an_ulp(-100, 100, portable_cos, exact_cos, "cos");
  expect_within_an_ulp(-1.5f, 1.5f, portable_tan, exact_tan, "tan");
}

TEST(PortableMath, SmallArgumentsAndExactPoints) {
  EXPECT_EQ(portable_sin(1e-20f), 1e-20f);
  EXPECT_EQ(portable_tan(1e-20f), 1e-20f);
  EXPECT_EQ(portable_cos(1e-20f), 1.0f);
  EXPECT_EQ(portable_cos(0.0f), 1.0f);
  EXPECT_EQ(portable_sin(std::numbers::pi_v<float> / 2), 1.0f);
  EXPECT_EQ(portable_tan(std::numbers::pi_v<float> / 4), 1.0f);
}

TEST(PortableMath, SpecialCasesAsC) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  for (const float x : {inf, -inf, nan}) {
    EXPECT_TRUE(std::isnan(portable_sin(x)));
    EXPECT_TRUE(std::isnan(portable_cos(x)));
    EXPECT_TRUE(std::isnan(portable_tan(x)));
  }
  EXPECT_TRUE(std::signbit(portable_sin(-0.0f)));
  EXPECT_TRUE(std::signbit(portable_tan(-0.0f)));
  EXPECT_FALSE(std::signbit(portable_sin(0.0f)));
  EXPECT_EQ(portable_cos(-0.0f), 1.0f);
}

}  // namespace
}  // namespace pms
