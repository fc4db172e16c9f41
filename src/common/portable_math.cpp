// fdlibm's __kernel_sin / __kernel_cos coefficients (Sun Microsystems, 1993) on [-pi/4, pi/4], after a
// two-constant Cody-Waite reduction (fdlibm's pio2_1, whose 33 bits make k * pio2_1 exact for |k| < 2^20).
#include "common/portable_math.h"

#include <cmath>

// A fused multiply-add rounds once where the expression says twice: contracting would give other bits on
// a machine with FMA than on one without (gcc contracts nothing in ISO C++ mode; this says so to clang,
// which em++ is).
#ifdef __clang__
#pragma STDC FP_CONTRACT OFF
#endif

namespace pms {
namespace {

constexpr double kTwoOverPi = 6.36619772367581382433e-01;
constexpr double kPio2Hi = 1.57079632673412561417e+00;  // the first 33 bits of pi/2
constexpr double kPio2Lo = 6.07710050650619224932e-11;  // pi/2 - kPio2Hi

// x = r + k pi/2 with |r| <= ~pi/4; k mod 4 picks the quadrant.
struct Reduced {
  double r;
  int quadrant;
};

Reduced reduce(double x) {
  const double k = std::floor(x * kTwoOverPi + 0.5);
  const double r = (x - k * kPio2Hi) - k * kPio2Lo;
  const double quadrant = k - 4 * std::floor(k * 0.25);  // k mod 4, exact for the k of any float
  return {r, int(quadrant)};
}

double kernel_sin(double x) {
  const double z = x * x;
  const double r =
      8.33333333332248946124e-03 +
      z * (-1.98412698298579493134e-04 +
           z * (2.75573137070700676789e-06 + z * (-2.50507602534068634195e-08 + z * 1.58969099521155010221e-10)));
  return x + z * x * (-1.66666666666666324348e-01 + z * r);
}

double kernel_cos(double x) {
  const double z = x * x;
  const double r =
      4.16666666666666019037e-02 +
      z * (-1.38888888888741095749e-03 +
           z * (2.48015872894767294178e-05 + z * (-2.75573143513906633035e-07 +
                                                  z * (2.08757232129817482790e-09 + z * -1.13596475577881948265e-11))));
  return (1.0 - 0.5 * z) + z * z * r;
}

// sin(x) for quadrant 0..3 of the reduced argument, or cos(x) with the quadrant one further on.
double sin_of(const Reduced& a) {
  switch (a.quadrant & 3) {
    case 0:
      return kernel_sin(a.r);
    case 1:
      return kernel_cos(a.r);
    case 2:
      return -kernel_sin(a.r);
    default:
      return -kernel_cos(a.r);
  }
}

bool special(float x) { return std::isnan(x) || std::isinf(x); }

}  // namespace

float portable_sin(float x) {
  if (special(x)) return NAN;
  if (x == 0) return x;  // keeps -0
  return float(sin_of(reduce(x)));
}

float portable_cos(float x) {
  if (special(x)) return NAN;
  Reduced a = reduce(x);
  ++a.quadrant;
  return float(sin_of(a));
}

float portable_tan(float x) {
  if (special(x)) return NAN;
  if (x == 0) return x;
  const Reduced a = reduce(x);
  const double s = kernel_sin(a.r), c = kernel_cos(a.r);
  return float(a.quadrant & 1 ? -c / s : s / c);  // tan(r + pi/2) = -cot(r)
}

}  // namespace pms
