// Unit normals as octahedral 2 x 16-bit snorm (Meyer et al. 2010): 32 bits instead of 96, ~1e-4 rad.
// Below the protocol layer so the builder codes split records offline on the same values the wire sends.
#pragma once
#include <cstdint>

namespace pms {

// The square's half width: a coordinate is an int16 in [-kOctahedralMax, kOctahedralMax].
constexpr int32_t kOctahedralMax = 32767;

// A zero or non-finite vector encodes as +z. The result is canonical, and decode_normal's result encodes
// back to the same pair.
void encode_normal(const float n[3], uint16_t q[2]);
void decode_normal(const uint16_t q[2], float n[3]);
// A point on the square's edge and its mirror image across the edge's middle are one normal (every corner
// is -z); the canonical one is what decode_normal's result encodes to: y >= 0 on the edges x = ±max, x >= 0
// on y = ±max, the corner (max, max). -32768 counts as -max.
void canonical_normal(uint16_t q[2]);
bool is_canonical_normal(const uint16_t q[2]);

// The octahedral square tiles the plane mirrored: beyond the edge x = max lies (max + e, y) = (max - e, -y),
// and likewise past the other three edges. A step between two nearby normals across an edge is short to
// the copy beyond it. `octahedral_step` gives the step from `from` to `to` (both canonical) with the fewest
// magnitude bits, to `to` or to a copy strictly outside the square; `octahedral_unstep` folds the end of a
// step back onto the square, false when it lies off the square and its four copies.
void octahedral_step(const uint16_t from[2], const uint16_t to[2], int64_t d[2]);
bool octahedral_unstep(const uint16_t from[2], const int64_t d[2], uint16_t to[2]);

}  // namespace pms
