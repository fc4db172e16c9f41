// Hoppe-97 refinement info (Hoppe 1997 §4), quantized as the .pms file stores it and the wire carries it.
#pragma once
#include <cstdint>

namespace pms {

// Hoppe-97 refinement info as stored and sent: quantized so every bound still holds after
// decoding (radius, mu, delta and cone angle rounded up). All modes evaluate these decoded
// values, so local, sender-, receiver-driven and DAG refinement agree on the mesh for a view.
// The precision is what a vsplit packet carries (65 bits per node with a cone, 43 without: two
// nodes per packet are most of a packet), so the file holds exactly what the wire can say.
struct RefineInfo {
  uint16_t radius;  // half-float bits of radius / scale, rounded toward +inf to kLengthKeptBits
  uint16_t mu;      // same, of mu / scale (uniform deviation)
  uint16_t delta;   // same, of delta / scale (deviation along the normal)
  uint16_t cone_x;  // octahedral-encoded cone axis: int16 in [-kAxisSteps, kAxisSteps] per coordinate
  uint16_t cone_y;
  uint16_t cone_angle;  // half-angle in units of (pi/2) / (kConeSteps + 1), rounded up; kNoCone = never back-facing
  friend bool operator==(const RefineInfo&, const RefineInfo&) = default;
};
static_assert(sizeof(RefineInfo) == 12);
constexpr uint16_t kNoCone = 0xFFFF;                       // the axis is then +z (0, 0)
constexpr uint32_t kLengthDroppedBits = 4;                 // low half-float mantissa bits that are always 0
constexpr uint32_t kLengthBits = 15 - kLengthDroppedBits;  // what is left without the sign
constexpr uint32_t kAxisBits = 11;                         // per octahedral coordinate, sign included
constexpr int16_t kAxisSteps = (1 << (kAxisBits - 1)) - 1;
constexpr uint32_t kConeAngleBits = 10;
constexpr uint16_t kConeSteps = (1 << kConeAngleBits) - 2;  // largest cone_angle below pi/2

// False for values quantize_refine never produces (negative or NaN lengths, dropped bits set, axis
// or angle out of range, a no-cone axis other than +z): the file reader and wire decoder reject them.
bool is_canonical(const RefineInfo& info);

// mu = delta = 0: qrefine's screen-space test is strict, so such a node never asks to be refined whatever
// its radius and cone. Every real leaf is one.
inline bool never_refines(const RefineInfo& info) { return info.mu == 0 && info.delta == 0; }
// The info as every mode delivers it (docs/protocol.md, RefineInfo): a node that never refines travels
// as one flag and decodes with radius 0 and no cone; any other info exactly as stored.
RefineInfo as_sent(const RefineInfo& info);

// Decoded, in model units.
struct RefineBounds {
  float radius = 0;  // sphere around the node's position bounding its descendants' input faces
  float mu = 0;      // deviation space D(mu, delta) around the normal (Hoppe 1997 §4.3)
  float delta = 0;
  float axis[3] = {0, 0, 1};
  float cone_angle = 0;  // radians; >= pi/2 (or kNoCone) means the cone test never culls
};

RefineInfo quantize_refine(const RefineBounds& bounds, float scale);
// One length as quantize_refine stores it: the smallest stored half that decodes to at least `value`.
uint16_t encode_length(float value, float scale);
RefineBounds dequantize_refine(const RefineInfo& info, float scale);

// Half-float helpers (exposed for tests): round toward +inf so decoded >= value for value >= 0.
uint16_t half_from_float_up(float value);
float float_from_half(uint16_t half);

}  // namespace pms
