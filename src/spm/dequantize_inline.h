// The decoding half of spm/quantize.cpp, inline: the adaptation loop decodes a node's RefineInfo when
// its walk first reaches it, thousands of times in a fresh mesh's first frame, and as calls the
// decoders cost more than the arithmetic. quantize.cpp's dequantize_refine and float_from_half are
// these functions, so every mode decodes the same bits.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "common/bit_cast.h"
#include "spm/refine_info.h"

namespace pms::dequantize_detail {

constexpr double kConeUnit = std::numbers::pi / 2 / (kConeSteps + 1);  // one step of RefineInfo::cone_angle

// A zero or broken scale (a model that is a single point) would turn every bound into NaN; such
// models keep their bounds unscaled instead. Encoder and decoder agree on this.
inline float effective_scale(float scale) { return scale > 0 && std::isfinite(scale) ? scale : 1.0f; }

inline float float_from_half(uint16_t half) {
  const uint32_t sign = uint32_t(half & 0x8000) << 16;
  const uint32_t exponent = (half >> 10) & 0x1F;
  const uint32_t mantissa = half & 0x3FF;
  if (exponent == 0) {  // zero or subnormal: exact in float
    const float magnitude = float(mantissa) * 0x1p-24f;
    return sign ? -magnitude : magnitude;
  }
  if (exponent == 31) return bit_cast<float>(sign | 0x7F800000 | mantissa << 13);  // inf / NaN
  return bit_cast<float>(sign | (exponent + 112) << 23 | mantissa << 13);
}

inline float decode_length(uint16_t half, float scale) { return float_from_half(half) * effective_scale(scale); }

// Octahedral decode (Meyer et al. 2010) of two int16 coordinates on a square of half width `steps` into
// a unit float vector: the cone axes (kAxisSteps) and the wire's normals (spm/octahedral_normal.h).
inline void decode_octahedral(uint16_t qx, uint16_t qy, float steps, float out[3]) {
  float x = std::max(float(int16_t(qx)) / steps, -1.0f), y = std::max(float(int16_t(qy)) / steps, -1.0f);
  const float z = 1.0f - std::abs(x) - std::abs(y);
  const float fold = std::max(-z, 0.0f);  // lower hemisphere is folded over the diagonals
  x += x >= 0 ? -fold : fold;
  y += y >= 0 ? -fold : fold;
  const float inv = 1.0f / std::sqrt(x * x + y * y + z * z);  // never 0: |x| + |y| + |z| >= 1 after folding
  out[0] = x * inv;
  out[1] = y * inv;
  out[2] = z * inv;
}

// The cone axis as dequantize_refine returns it.
inline void decode_axis(uint16_t qx, uint16_t qy, float axis[3]) { decode_octahedral(qx, qy, float(kAxisSteps), axis); }

inline float decode_cone_angle(uint16_t units) {
  return units == kNoCone ? std::numbers::pi_v<float> : float(units * kConeUnit);
}

// With `effective` = effective_scale(scale), worked out once by a caller that decodes many nodes of one
// model (the adaptation loop): the same bits as dequantize_refine_inline.
inline RefineBounds dequantize_refine_scaled(const RefineInfo& info, float effective) {
  RefineBounds b;
  b.radius = float_from_half(info.radius) * effective;
  b.mu = float_from_half(info.mu) * effective;
  b.delta = float_from_half(info.delta) * effective;
  decode_axis(info.cone_x, info.cone_y, b.axis);
  b.cone_angle = decode_cone_angle(info.cone_angle);
  return b;
}

inline RefineBounds dequantize_refine_inline(const RefineInfo& info, float scale) {
  return dequantize_refine_scaled(info, effective_scale(scale));
}

}  // namespace pms::dequantize_detail
