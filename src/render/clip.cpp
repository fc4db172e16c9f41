// Homogeneous clipping (Sutherland & Hodgman 1974; Blinn & Newell 1978, "Clipping using homogeneous
// coordinates"): a triangle that crosses the near plane is cut there in clip space, before the divide by
// w, so a vertex behind the eye never flips to the other side of the screen. Triangles reaching past the
// guard band are cut too, which keeps the fixed-point coordinates in range.
//
// Watertightness: the point where an edge crosses a plane is always computed from its inside end towards
// its outside end, so the two faces sharing that edge produce the same bits, and the pieces of the edge
// they rasterize meet exactly.
#include "render/raster_internal.h"

namespace pms::render_detail {
namespace {

enum Plane { kNear, kGuardLeft, kGuardRight, kGuardBottom, kGuardTop };

float distance(Plane plane, const float c[4], const Frame& frame) {
  switch (plane) {
    case kNear:
      return c[2] + c[3];
    case kGuardLeft:
      return c[0] + frame.guard_x * c[3];
    case kGuardRight:
      return frame.guard_x * c[3] - c[0];
    case kGuardBottom:
      return c[1] + frame.guard_y * c[3];
    case kGuardTop:
      return frame.guard_y * c[3] - c[1];
  }
  return 0;
}

ClipVertex intersect(const ClipVertex& inside, float d_inside, const ClipVertex& outside, float d_outside) {
  const float t = d_inside / (d_inside - d_outside);
  ClipVertex v;
  for (int k = 0; k < 4; ++k) v.c[k] = inside.c[k] + t * (outside.c[k] - inside.c[k]);
  for (int k = 0; k < 3; ++k) v.rgb[k] = inside.rgb[k] + t * (outside.rgb[k] - inside.rgb[k]);
  return v;
}

int clip_against(Plane plane, ClipVertex poly[kMaxPolygon], int count, const Frame& frame) {
  float d[kMaxPolygon];
  bool any_outside = false;
  for (int i = 0; i < count; ++i) {
    d[i] = distance(plane, poly[i].c, frame);
    any_outside |= !(d[i] >= 0);
  }
  if (!any_outside) return count;
  ClipVertex out[kMaxPolygon];
  int n = 0;
  // n + 2 <= kMaxPolygon only fails for a polygon made non-convex by rounding; dropping a sliver of it
  // beats writing past the array.
  for (int i = 0; i < count && n + 2 <= kMaxPolygon; ++i) {
    const int j = i + 1 == count ? 0 : i + 1;
    const bool in_i = d[i] >= 0, in_j = d[j] >= 0;
    if (in_i) out[n++] = poly[i];
    if (in_i && !in_j) out[n++] = intersect(poly[i], d[i], poly[j], d[j]);
    if (!in_i && in_j) out[n++] = intersect(poly[j], d[j], poly[i], d[i]);
  }
  for (int i = 0; i < n; ++i) poly[i] = out[i];
  return n;
}

}  // namespace

int clip_polygon(ClipVertex poly[kMaxPolygon], int count, uint8_t planes, const Frame& frame) {
  // A convex polygon gains at most one vertex per plane: 3 + 5 = 8 (kMaxPolygon leaves room to spare).
  if (planes & kOutNear) count = clip_against(kNear, poly, count, frame);
  if (planes & kOutGuard)
    for (const Plane plane : {kGuardLeft, kGuardRight, kGuardBottom, kGuardTop})
      if (count >= 3) count = clip_against(plane, poly, count, frame);
  return count;
}

}  // namespace pms::render_detail
