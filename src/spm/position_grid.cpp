// Positions on a per-axis grid over the model's bounding box (docs/internals.md, "Geometry";
// docs/protocol.md, "Quantization").
// Client and server must agree bit for bit on dequantized positions (they feed qrefine), so
// dequantization is a fixed sequence of double operations, one per statement: no compiler may fuse
// them into an FMA (clang's default -ffp-contract=on contracts only within an expression), and IEEE
// double arithmetic rounds the same on every platform, wasm included.
#include <algorithm>
#include <cmath>

#include "spm/position_grid.h"

#include "common/bit_cast.h"

namespace pms {
namespace {

constexpr uint32_t kRawBits = 32;      // positions as their float32 bits
constexpr uint32_t kMaxGridBits = 24;  // a float has 24 significant bits: a finer grid adds nothing

double grid_steps(uint32_t bits) { return double((uint64_t(1) << bits) - 1); }

}  // namespace

bool valid_position_bits(uint32_t bits) { return (bits >= 1 && bits <= kMaxGridBits) || bits == kRawBits; }

void quantize_position(const PositionGrid& grid, const float p[3], uint32_t q[3]) {
  if (grid.bits == kRawBits) {
    for (int i = 0; i < 3; ++i) q[i] = bit_cast<uint32_t>(p[i]);
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
    for (int i = 0; i < 3; ++i) p[i] = bit_cast<float>(q[i]);
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

}  // namespace pms
