// The inner loop: one tile, its triangles in face order, half-space rasterization with exact int64 edge
// functions (Pineda 1988) stepped per pixel, a less-than float depth test, and perspective-correct colour
// (attributes weighted by barycentric / w, renormalized; Heckbert & Moreton 1991).
//
// Every value written to a pixel depends only on the triangle and the pixel's coordinates, never on where
// the tile or the bounding box starts, so the image is the same for any tile schedule.
#include <algorithm>
#include <cmath>

#include "render/raster_internal.h"
#include "spm/vertex_id.h"

namespace pms::render_detail {
namespace {

struct TileRect {
  int32_t x0, y0, x1, y1;  // inclusive
};

TileRect tile_rect(const Frame& frame, uint32_t tile) {
  const int32_t x0 = int32_t(tile % frame.tiles_x) << kTileBits, y0 = int32_t(tile / frame.tiles_x) << kTileBits;
  return {x0, y0, std::min(x0 + kTileSize, int32_t(frame.width)) - 1,
          std::min(y0 + kTileSize, int32_t(frame.height)) - 1};
}

uint8_t to_byte(float value) {
  const float v = std::min(value + 0.5f, 255.0f);
  return uint8_t(v > 0 ? v : 0);
}

// Pixel offsets k in [first, last] of a row where every edge value w + k * step seen so far is >= 0.
struct Span {
  int64_t first, last;
  void clip(int64_t w, int64_t step) {
    if (step > 0) {
      if (w < 0) first = std::max(first, (-w + step - 1) / step);
    } else if (step < 0) {
      if (w < 0) last = -1;
      else last = std::min(last, w / -step);
    } else if (w < 0) {
      last = -1;
    }
  }
};
constexpr int32_t kSpanMinWidth = 8;

template <bool kShade>
void draw(const Tri& t, const TileRect& rect, const Frame& frame, const Target& target) {
  PixelBox box = pixel_box(t.x[0], t.x[1], t.x[2], t.y[0], t.y[1], t.y[2], frame);
  box.x0 = std::max(box.x0, rect.x0);
  box.y0 = std::max(box.y0, rect.y0);
  box.x1 = std::min(box.x1, rect.x1);
  box.y1 = std::min(box.y1, rect.y1);
  if (box.x0 > box.x1 || box.y0 > box.y1) return;

  const Edges e = edge_setup(t.x, t.y);
  const int64_t area =
      (int64_t(t.x[1]) - t.x[0]) * (int64_t(t.y[2]) - t.y[0]) - (int64_t(t.y[1]) - t.y[0]) * (int64_t(t.x[2]) - t.x[0]);
  const float inv_area = 1.0f / float(area);
  const float dz1 = t.z[1] - t.z[0], dz2 = t.z[2] - t.z[0];
  float rgb[3][3] = {};  // [corner][channel]
  if constexpr (kShade)
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) rgb[i][k] = float((t.color[i] >> (8 * k)) & 255);
  const int64_t step[3] = {e.a[0] * kSubpixel, e.a[1] * kSubpixel, e.a[2] * kSubpixel};
  const int64_t x_start = pixel_center(box.x0);

  // Wide boxes scan only the span of each row inside all three edges; narrow ones test every pixel, which
  // costs less than the span's divisions. Both visit exactly the pixels with w0, w1, w2 >= 0.
  const bool spans = box.x1 - box.x0 >= kSpanMinWidth;
  for (int32_t py = box.y0; py <= box.y1; ++py) {
    const int64_t y = pixel_center(py);
    int64_t w0 = e.a[0] * x_start + e.b[0] * y + e.c[0] - e.bias[0];
    int64_t w1 = e.a[1] * x_start + e.b[1] * y + e.c[1] - e.bias[1];
    int64_t w2 = e.a[2] * x_start + e.b[2] * y + e.c[2] - e.bias[2];
    int32_t first = box.x0, last = box.x1;
    if (spans) {
      Span span{0, box.x1 - box.x0};
      span.clip(w0, step[0]);
      span.clip(w1, step[1]);
      span.clip(w2, step[2]);
      if (span.first > span.last) continue;
      first = box.x0 + span.first;
      last = box.x0 + span.last;
      w0 += span.first * step[0];
      w1 += span.first * step[1];
      w2 += span.first * step[2];
    }
    const size_t row = size_t(py) * frame.width;
    for (int32_t px = first; px <= last; ++px, w0 += step[0], w1 += step[1], w2 += step[2]) {
      if ((w0 | w1 | w2) < 0) continue;
      // Unbiased edge values are the barycentric weights times the doubled area.
      const float l0 = float(w0 + e.bias[0]), l1 = float(w1 + e.bias[1]), l2 = float(w2 + e.bias[2]);
      const float z = t.z[0] + (l1 * dz1 + l2 * dz2) * inv_area;
      const size_t pixel = row + size_t(px);
      if (!(z < target.depth[pixel])) continue;
      target.depth[pixel] = z;
      target.face_id[pixel] = t.face;
      if constexpr (!kShade) continue;
      const float q0 = l0 * t.inv_w[0], q1 = l1 * t.inv_w[1], q2 = l2 * t.inv_w[2];
      const float norm = 1.0f / (q0 + q1 + q2);
      uint8_t* out = target.rgb + 3 * pixel;
      for (int k = 0; k < 3; ++k) out[k] = to_byte((q0 * rgb[0][k] + q1 * rgb[1][k] + q2 * rgb[2][k]) * norm);
    }
  }
}

template <bool kShade>
void draw_all(const Frame& frame, uint32_t tile, const Tri* tris, const uint32_t* entries, size_t begin, size_t end,
              const Target& target) {
  const TileRect rect = tile_rect(frame, tile);
  // A tile's triangles are scattered through its chunk's array: fetch a few ahead, or the loads of the
  // records, not the pixels, dominate on dense meshes.
  constexpr size_t kPrefetch = 8;
  for (size_t i = begin; i < end; ++i) {
    if (i + kPrefetch < end) __builtin_prefetch(&tris[entries[i + kPrefetch]]);
    draw<kShade>(tris[entries[i]], rect, frame, target);
  }
}

}  // namespace

void raster_tile(const Frame& frame, uint32_t tile, const Tri* tris, const uint32_t* entries, size_t begin, size_t end,
                 const Target& target) {
  if (target.rgb) draw_all<true>(frame, tile, tris, entries, begin, end, target);
  else draw_all<false>(frame, tile, tris, entries, begin, end, target);
}

void clear_tile(const Frame& frame, uint32_t tile, const Target& target) {
  const TileRect rect = tile_rect(frame, tile);
  const size_t width = size_t(rect.x1 - rect.x0 + 1);
  for (int32_t py = rect.y0; py <= rect.y1; ++py) {
    const size_t first = size_t(py) * frame.width + size_t(rect.x0);
    std::fill_n(target.depth + first, width, 1.0f);
    std::fill_n(target.face_id + first, width, kNone);
    if (!target.rgb) continue;
    for (size_t pixel = first; pixel < first + width; ++pixel)
      for (int k = 0; k < 3; ++k) target.rgb[3 * pixel + k] = target.background[k];
  }
}

}  // namespace pms::render_detail
