// Quantized refinement info (Hoppe 1997 §4; kim-lee-kobbelt §5 sends it with every vsplit).
// Every bound is rounded *outward*: the decoded sphere, deviation space and normal cone contain
// whatever the exact ones contained, so refinement decisions on decoded values stay conservative.
// Half floats: IEEE 754 binary16 with the low kLengthDroppedBits mantissa bits dropped (about 1.6 %
// precision: bounds a little loose are cheap, bits on the wire are not). Cone axis: octahedral encoding
// (Meyer et al. 2010, "On floating-point normal vectors"), kAxisBits-bit snorm per coordinate.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/bit_cast.h"
#include "spm/dequantize_inline.h"
#include "spm/refine_info.h"

namespace pms {
using namespace dequantize_detail;
namespace {

constexpr uint16_t kHalfInfinity = 0x7C00;
constexpr float kHalfMax = 65504.0f;
constexpr double kHalfPi = std::numbers::pi / 2;
// Consumers test normals against the decoded float axis, which is unit length only to ~1e-7:
// widen every cone by a micro-radian so that float slack never leaves a normal outside.
constexpr double kConeSlack = 1e-6;

constexpr uint16_t kDroppedMask = (1u << kLengthDroppedBits) - 1;

// The next half at or above `half` whose dropped bits are 0; a carry correctly bumps the exponent
// (and the largest finite values round up to infinity, 0x7C00).
uint16_t round_up_to_kept_bits(uint32_t half) {
  return uint16_t(std::min<uint32_t>((half + kDroppedMask) & ~uint32_t(kDroppedMask), kHalfInfinity));
}

// Angle between unit `a` and the (nearly unit) float vector `b`; atan2 stays accurate for tiny
// angles, where acos(dot) loses half its digits.
double angle_to(const double a[3], const float b_in[3]) {
  double b[3] = {b_in[0], b_in[1], b_in[2]};
  const double len = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  for (double& c : b) c /= len;
  const double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2], cz = a[0] * b[1] - a[1] * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
}

struct EncodedAxis {
  uint16_t x = 0, y = 0;
  double error = 0;  // angle between the exact axis and the decoded one
};

// Encodes unit `axis`, trying the four snorm roundings around the exact octahedral point and
// keeping the one whose decoded axis is closest (the error widens the cone, so smaller is better).
EncodedAxis encode_axis(const double axis[3]) {
  const double l1 = std::abs(axis[0]) + std::abs(axis[1]) + std::abs(axis[2]);
  double px = axis[0] / l1, py = axis[1] / l1;
  if (axis[2] < 0) {
    const double fx = (1 - std::abs(py)) * (px >= 0 ? 1 : -1);
    const double fy = (1 - std::abs(px)) * (py >= 0 ? 1 : -1);
    px = fx;
    py = fy;
  }
  // Rank the candidates by cosine (cheap); only the winner's angle needs atan2.
  EncodedAxis best{0, 0, INFINITY};
  double best_cos = -INFINITY;
  for (int i = 0; i < 4; ++i) {
    const double steps = kAxisSteps, sx = px * steps, sy = py * steps;
    const auto qx = int16_t(std::clamp((i & 1) ? std::ceil(sx) : std::floor(sx), -steps, steps));
    const auto qy = int16_t(std::clamp((i & 2) ? std::ceil(sy) : std::floor(sy), -steps, steps));
    float decoded[3];
    decode_axis(uint16_t(qx), uint16_t(qy), decoded);
    const double len =
        std::sqrt(double(decoded[0]) * decoded[0] + double(decoded[1]) * decoded[1] + double(decoded[2]) * decoded[2]);
    const double cosine = (axis[0] * decoded[0] + axis[1] * decoded[1] + axis[2] * decoded[2]) / len;
    if (cosine > best_cos) {
      best_cos = cosine;
      best = {uint16_t(qx), uint16_t(qy), 0};
    }
  }
  float decoded[3];
  decode_axis(best.x, best.y, decoded);
  best.error = angle_to(axis, decoded);
  return best;
}

// Smallest step count whose decoded angle covers `angle`, or kNoCone once the cone reaches pi/2
// (a half-space of normals: the back-face test can never cull it).
uint16_t encode_cone_angle(double angle) {
  if (!(angle < kHalfPi)) return kNoCone;
  auto units = uint32_t(std::ceil(angle / kConeUnit));
  while (decode_cone_angle(uint16_t(units)) < angle) ++units;
  return decode_cone_angle(uint16_t(units)) >= kHalfPi ? kNoCone : uint16_t(units);
}

}  // namespace

uint16_t half_from_float_up(float value) {
  if (std::isnan(value) || value > kHalfMax) return kHalfInfinity;
  if (!(value > 0)) return 0;
  const uint32_t bits = bit_cast<uint32_t>(value);
  const int exponent = int(bits >> 23) - 127;
  const uint32_t mantissa = bits & 0x7FFFFF;
  if (exponent >= -14) {  // a normal half: keep 10 of the 23 mantissa bits, round the rest up
    const uint32_t half = uint32_t(exponent + 15) << 10 | mantissa >> 13;
    return uint16_t(half + ((mantissa & 0x1FFF) != 0));  // a carry correctly bumps the exponent
  }
  if (exponent == -127) return 1;  // float subnormal: far below the smallest half subnormal
  // Subnormal half = m * 2^-24. value = significand * 2^(exponent - 23), so m = significand >> shift.
  const uint32_t significand = mantissa | 0x800000;
  const int shift = -(exponent + 1);  // >= 14
  if (shift >= 24) return 1;
  const uint32_t m = significand >> shift;
  return uint16_t(m + ((significand & ((1u << shift) - 1)) != 0));  // m == 1024 is the smallest normal
}

float float_from_half(uint16_t half) { return dequantize_detail::float_from_half(half); }

// Smallest kept-bits half h with decode_length(h) >= value: the division and the multiply each
// round, so the first guess is checked against the exact decoder and bumped (at most a step).
uint16_t encode_length(float value, float scale) {
  if (std::isnan(value)) return kHalfInfinity;  // unknown bound: never culls, always refines
  if (!(value > 0)) return 0;
  uint16_t half = round_up_to_kept_bits(half_from_float_up(value / effective_scale(scale)));
  while (half < kHalfInfinity && decode_length(half, scale) < value) half = round_up_to_kept_bits(half + 1u);
  return half;
}

RefineInfo quantize_refine(const RefineBounds& bounds, float scale) {
  RefineInfo info{};
  info.radius = encode_length(bounds.radius, scale);
  info.mu = encode_length(bounds.mu, scale);
  info.delta = encode_length(bounds.delta, scale);

  double axis[3] = {bounds.axis[0], bounds.axis[1], bounds.axis[2]};
  const double length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  // Without a cone the axis is never read: it is stored as +z, (0, 0), so the wire can leave it out.
  info.cone_angle = kNoCone;
  const double angle = std::max<double>(bounds.cone_angle, 0.0);
  if (!(length > 0) || !std::isfinite(length) || std::isnan(bounds.cone_angle) || angle >= kHalfPi) return info;
  for (double& c : axis) c /= length;
  const EncodedAxis e = encode_axis(axis);
  // Triangle inequality: a normal within `angle` of the exact axis is within angle + error of the
  // decoded one.
  info.cone_angle = encode_cone_angle(angle + e.error + kConeSlack);
  if (info.cone_angle == kNoCone) return info;
  info.cone_x = e.x;
  info.cone_y = e.y;
  return info;
}

bool is_canonical(const RefineInfo& info) {
  const auto length_ok = [](uint16_t half) { return half <= kHalfInfinity && (half & kDroppedMask) == 0; };
  const auto axis_ok = [](uint16_t q) { return int16_t(q) >= -kAxisSteps && int16_t(q) <= kAxisSteps; };
  if (!length_ok(info.radius) || !length_ok(info.mu) || !length_ok(info.delta)) return false;
  if (info.cone_angle == kNoCone) return info.cone_x == 0 && info.cone_y == 0;
  return info.cone_angle <= kConeSteps && axis_ok(info.cone_x) && axis_ok(info.cone_y);
}

RefineInfo as_sent(const RefineInfo& info) {
  if (!never_refines(info)) return info;
  RefineInfo zero{};
  zero.cone_angle = kNoCone;
  return zero;
}

RefineBounds dequantize_refine(const RefineInfo& info, float scale) { return dequantize_refine_inline(info, scale); }

}  // namespace pms
