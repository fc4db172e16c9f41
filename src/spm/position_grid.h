// Quantized positions: the numbers every mode evaluates the refinement criteria on (docs/protocol.md,
// "Quantization"). Below the protocol layer so the builder can code split records offline on the same grid.
#pragma once
#include <cstdint>

namespace pms {

constexpr uint32_t kDefaultPositionBits = 16;

// Positions on the wire: `bits` per axis on a uniform grid over the model's bounding box (1..24 bits),
// or the raw float32 bits (32). Client and server must evaluate refinement criteria on the same numbers,
// so the server quantizes the model's exact positions when it encodes and evaluates qrefine on
// dequantize(quantize(p)) (snap_position); the client only ever sees the dequantized values.
struct PositionGrid {
  float min[3] = {0, 0, 0};
  float max[3] = {0, 0, 0};
  uint32_t bits = kDefaultPositionBits;
};
bool valid_position_bits(uint32_t bits);  // 1..24 or 32
// Clamps to the box; non-finite coordinates become the box minimum (grid) or stay as they are (32 bits).
void quantize_position(const PositionGrid& grid, const float p[3], uint32_t q[3]);
void dequantize_position(const PositionGrid& grid, const uint32_t q[3], float p[3]);
void snap_position(const PositionGrid& grid, const float p[3], float out[3]);  // dequantize(quantize(p))
// Largest |dequantize(quantize(p)) - p| per axis for p inside the box (half a grid step, plus float rounding).
float position_error_bound(const PositionGrid& grid, int axis);

}  // namespace pms
