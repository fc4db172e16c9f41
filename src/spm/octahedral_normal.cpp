// Normals on the wire and in split records, octahedral (Meyer et al. 2010, "On floating-point normal
// vectors"); positions are spm/position_grid.cpp.
#include "spm/octahedral_normal.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "spm/dequantize_inline.h"

namespace pms {
namespace {

uint16_t snorm16(float v) { return uint16_t(int16_t(std::lround(std::clamp(v, -1.0f, 1.0f) * float(kOctahedralMax)))); }

}  // namespace

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
  canonical_normal(q);
}

void canonical_normal(uint16_t q[2]) {
  const int16_t x = int16_t(q[0]), y = int16_t(q[1]);
  const bool x_edge = x == kOctahedralMax || x <= -kOctahedralMax, y_edge = y == kOctahedralMax || y <= -kOctahedralMax;
  if (x_edge && y_edge) {  // every corner is -z
    q[0] = q[1] = uint16_t(kOctahedralMax);
  } else if (x_edge) {
    q[0] = uint16_t(int16_t(x > 0 ? kOctahedralMax : -kOctahedralMax));
    q[1] = uint16_t(int16_t(std::abs(y)));
  } else if (y_edge) {
    q[0] = uint16_t(int16_t(std::abs(x)));
    q[1] = uint16_t(int16_t(y > 0 ? kOctahedralMax : -kOctahedralMax));
  }
}

namespace {

int64_t coordinate(uint16_t q) { return int16_t(q); }
uint32_t step_bits(int64_t dx, int64_t dy) {
  return uint32_t(std::bit_width(uint64_t(std::abs(dx)))) + uint32_t(std::bit_width(uint64_t(std::abs(dy))));
}

}  // namespace

void octahedral_step(const uint16_t from[2], const uint16_t to[2], int64_t d[2]) {
  constexpr int64_t m = kOctahedralMax;
  const int64_t xs = coordinate(from[0]), ys = coordinate(from[1]), xt = coordinate(to[0]), yt = coordinate(to[1]);
  // `to` itself, then its copies beyond the right, left, top and bottom edges; a copy counts only strictly
  // outside the square (on an edge it would be `to`'s mirror image, which the canonical form excludes).
  const int64_t copies[5][2] = {{xt, yt}, {2 * m - xt, -yt}, {-2 * m - xt, -yt}, {-xt, 2 * m - yt}, {-xt, -2 * m - yt}};
  const bool outside[5] = {true, xt<m, xt> - m, yt<m, yt> - m};
  d[0] = xt - xs, d[1] = yt - ys;
  for (int i = 1; i < 5; ++i)
    if (outside[i] && step_bits(copies[i][0] - xs, copies[i][1] - ys) < step_bits(d[0], d[1]))
      d[0] = copies[i][0] - xs, d[1] = copies[i][1] - ys;
}

bool octahedral_unstep(const uint16_t from[2], const int64_t d[2], uint16_t to[2]) {
  constexpr int64_t m = kOctahedralMax;
  if (std::abs(d[0]) > 4 * m || std::abs(d[1]) > 4 * m) return false;  // reaches no copy; and no overflow below
  int64_t x = coordinate(from[0]) + d[0], y = coordinate(from[1]) + d[1];
  if (x > m) x = 2 * m - x, y = -y;
  else if (x < -m) x = -2 * m - x, y = -y;
  else if (y > m) y = 2 * m - y, x = -x;
  else if (y < -m) y = -2 * m - y, x = -x;
  if (std::abs(x) > m || std::abs(y) > m) return false;
  to[0] = uint16_t(int16_t(x)), to[1] = uint16_t(int16_t(y));
  return true;
}

bool is_canonical_normal(const uint16_t q[2]) {
  uint16_t c[2] = {q[0], q[1]};
  canonical_normal(c);
  return c[0] == q[0] && c[1] == q[1];
}

void decode_normal(const uint16_t q[2], float n[3]) {
  dequantize_detail::decode_octahedral(q[0], q[1], float(kOctahedralMax), n);
}

}  // namespace pms
