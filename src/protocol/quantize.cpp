// Quantized geometry on the wire: positions on a per-axis grid over the model's bounding box
// (docs/internals.md, "Geometry"; docs/protocol.md, "Quantization"), normals octahedral (Meyer et al. 2010,
// "On floating-point normal vectors").
// Client and server must agree bit for bit on dequantized positions (they feed qrefine), so
// dequantization is a fixed sequence of double operations, one per statement: no compiler may fuse
// them into an FMA (clang's default -ffp-contract=on contracts only within an expression), and IEEE
// double arithmetic rounds the same on every platform, wasm included.
#include <algorithm>
#include <bit>
#include <cmath>

#include "protocol/position_grid.h"
#include "protocol/wire_internal.h"

namespace pms::protocol {
namespace {

constexpr uint32_t kRawBits = 32;  // positions as their float32 bits
constexpr uint32_t kMaxGridBits = 24;  // a float has 24 significant bits: a finer grid adds nothing

double grid_steps(uint32_t bits) { return double((uint64_t(1) << bits) - 1); }

uint16_t snorm16(float v) { return uint16_t(int16_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f))); }
float from_snorm16(uint16_t bits) { return std::max(float(int16_t(bits)) / 32767.0f, -1.0f); }

}  // namespace

bool valid_position_bits(uint32_t bits) { return (bits >= 1 && bits <= kMaxGridBits) || bits == kRawBits; }

void quantize_position(const PositionGrid& grid, const float p[3], uint32_t q[3]) {
  if (grid.bits == kRawBits) {
    for (int i = 0; i < 3; ++i) q[i] = std::bit_cast<uint32_t>(p[i]);
    return;
  }
  const double steps = grid_steps(grid.bits);
  for (int i = 0; i < 3; ++i) {
    const double extent = double(grid.max[i]) - double(grid.min[i]);
    const double t = extent > 0 ? (double(p[i]) - double(grid.min[i])) / extent * steps : 0.0;
    // NaN fails both comparisons and lands on 0, like a coordinate below the box.
    q[i] = t >= steps ? uint32_t(steps) : t > 0 ? uint32_t(std::lround(t)) : 0;
  }
}

void dequantize_position(const PositionGrid& grid, const uint32_t q[3], float p[3]) {
  if (grid.bits == kRawBits) {
    for (int i = 0; i < 3; ++i) p[i] = std::bit_cast<float>(q[i]);
    return;
  }
  const double steps = grid_steps(grid.bits);
  for (int i = 0; i < 3; ++i) {
    const double extent = double(grid.max[i]) - double(grid.min[i]);
    const double fraction = double(q[i]) / steps;
    const double offset = fraction * extent;
    const double value = double(grid.min[i]) + offset;
    p[i] = std::min(float(value), grid.max[i]);
  }
}

void snap_position(const PositionGrid& grid, const float p[3], float out[3]) {
  uint32_t q[3];
  quantize_position(grid, p, q);
  dequantize_position(grid, q, out);
}

float position_error_bound(const PositionGrid& grid, int axis) {
  if (grid.bits == kRawBits) return 0;
  const double extent = double(grid.max[axis]) - double(grid.min[axis]);
  if (!(extent > 0)) return 0;  // a flat axis decodes to its one value exactly
  const double magnitude = std::max(std::abs(double(grid.min[axis])), std::abs(double(grid.max[axis])));
  // Half a step from rounding to the grid, plus the final rounding to float (half an ulp at the box's
  // largest magnitude, taken as 2^-24 relative) and a hair for the double arithmetic.
  return float(extent / grid_steps(grid.bits) / 2 + magnitude * 0x1p-24 * 1.01 + extent * 0x1p-50);
}

void encode_normal(const float n[3], uint16_t q[2]) {
  const float l1 = std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]);
  if (!(l1 > 0) || !std::isfinite(l1)) {  // no direction: +z, like the decoder's (0, 0)
    q[0] = q[1] = 0;
    return;
  }
  float x = n[0] / l1, y = n[1] / l1;
  if (n[2] < 0) {  // fold the lower hemisphere over the diagonals
    const float fx = (1 - std::abs(y)) * (x >= 0 ? 1.0f : -1.0f);
    const float fy = (1 - std::abs(x)) * (y >= 0 ? 1.0f : -1.0f);
    x = fx;
    y = fy;
  }
  q[0] = snorm16(x);
  q[1] = snorm16(y);
}

void decode_normal(const uint16_t q[2], float n[3]) {
  float x = from_snorm16(q[0]), y = from_snorm16(q[1]);
  const float z = 1.0f - std::abs(x) - std::abs(y);
  const float fold = std::max(-z, 0.0f);
  x += x >= 0 ? -fold : fold;
  y += y >= 0 ? -fold : fold;
  const float inv = 1.0f / std::sqrt(x * x + y * y + z * z);  // never 0: |x| + |y| + |z| >= 1 after folding
  n[0] = x * inv;
  n[1] = y * inv;
  n[2] = z * inv;
}

}  // namespace pms::protocol
