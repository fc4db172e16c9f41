// Shared by the render layer's .cpp files only: the frame constants, per-vertex and per-triangle records,
// and the fixed-point edge functions that both the binning pass and the tile rasterizer evaluate (they
// must agree bit for bit, or a triangle dropped early would differ from one rasterized late).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "render/render.h"

namespace pms::render_detail {

// Screen positions snap to 1/256 pixel (24.8 fixed point); edge functions are exact in int64, which is
// what makes the fill rule exact: a pixel centre on a shared edge is tested with the same integers by
// both triangles.
constexpr int kSubpixelBits = 8;
constexpr int32_t kSubpixel = 1 << kSubpixelBits;
constexpr int32_t kHalfPixel = kSubpixel / 2;
constexpr int kTileBits = 6;  // 64 x 64 pixel tiles
constexpr int kTileSize = 1 << kTileBits;
// Vertices farther than this outside the viewport are clipped (guard band), so fixed-point coordinates
// stay below 2^27 and edge-function products below 2^58.
constexpr float kGuardPixels = float(1 << 18);
// Convex polygon after clipping a triangle against the near plane and 4 guard planes: 3 + 5 vertices,
// with room to spare for rounding.
constexpr int kMaxPolygon = 12;

// Outcodes per vertex. A face is dropped when all three corners share one of kCullMask's bits, and
// clipped when any corner has a kClipMask bit.
enum : uint8_t {
  kOutLeft = 1,
  kOutRight = 2,
  kOutBottom = 4,
  kOutTop = 8,
  kOutFar = 16,
  kOutNear = 32,      // z < -w: in front of the near plane or behind the eye, no valid projection
  kOutGuard = 64,     // beyond the guard band in x or y
  kOutInvalid = 128,  // non-finite position: the face is dropped
};
constexpr uint8_t kCullMask = kOutLeft | kOutRight | kOutBottom | kOutTop | kOutFar | kOutNear;
constexpr uint8_t kClipMask = kOutNear | kOutGuard;

struct Frame {
  uint32_t width = 0, height = 0;
  float half_width = 0, half_height = 0;
  float guard_x = 0, guard_y = 0;  // guard band in NDC: |x| <= guard_x * w
  uint32_t tiles_x = 0, tiles_y = 0;
};
Frame make_frame(const ViewParams& view);

struct ScreenVertex {
  int32_t x, y;  // 24.8 fixed point, y down (row 0 at the top)
  float z;       // NDC depth
  float inv_w;   // 1 / clip w, for perspective-correct interpolation
};

// The one projection both the vertex stage and the clipper use, so a vertex shared by a clipped and an
// unclipped face lands on the same fixed-point position.
inline int32_t to_fixed(float pixels) {
  const float scaled = pixels * float(kSubpixel);
  return int32_t(scaled + (scaled >= 0 ? 0.5f : -0.5f));
}
inline ScreenVertex project(const float clip[4], const Frame& frame) {
  const float inv_w = 1.0f / clip[3];
  return {to_fixed((clip[0] * inv_w + 1.0f) * frame.half_width), to_fixed((1.0f - clip[1] * inv_w) * frame.half_height),
          clip[2] * inv_w, inv_w};
}

inline uint8_t outcode(const float clip[4], const Frame& frame) {
  const float x = clip[0], y = clip[1], z = clip[2], w = clip[3];
  // x - x is 0 for finite x and NaN otherwise: one test for all four.
  if (!((x - x) + (y - y) + (z - z) + (w - w) == 0)) return kOutInvalid;
  uint8_t code = 0;
  if (x < -w) code |= kOutLeft;
  if (x > w) code |= kOutRight;
  if (y < -w) code |= kOutBottom;
  if (y > w) code |= kOutTop;
  if (z > w) code |= kOutFar;
  if (z < -w) code |= kOutNear;
  if (x < -frame.guard_x * w || x > frame.guard_x * w || y < -frame.guard_y * w || y > frame.guard_y * w)
    code |= kOutGuard;
  return code;
}

// Everything the tile pass needs about one (possibly clipped) triangle: 64 bytes, one cache line.
// Corners are ordered so the edge functions below are positive inside.
struct Tri {
  int32_t x[3], y[3];
  float z[3], inv_w[3];
  uint32_t color[3];  // shaded RGB, 8 bits each (r | g << 8 | b << 16)
  uint32_t face;
};
static_assert(sizeof(Tri) == 64);

// E_i(p) = a[i] * px + b[i] * py + c[i] for edge i (the edge opposite corner i, from corner i+1 to i+2),
// px/py in fixed point. With positive area, E_i >= 0 inside and E_i / (E_0 + E_1 + E_2) is corner i's
// barycentric weight. Top-left rule (y down): an edge with dy < 0, or dy == 0 and dx > 0, owns the pixel
// centres on it; `bias` is 0 for those edges and 1 for the others, so "inside" is E_i - bias_i >= 0 for
// all three. A shared edge runs in opposite directions in its two triangles, so exactly one owns it.
struct Edges {
  int64_t a[3], b[3], c[3];
  int64_t bias[3];
};
inline Edges edge_setup(const int32_t x[3], const int32_t y[3]) {
  Edges e;
  for (int i = 0; i < 3; ++i) {
    const int j = i == 2 ? 0 : i + 1, k = j == 2 ? 0 : j + 1;
    const int64_t dx = int64_t(x[k]) - x[j], dy = int64_t(y[k]) - y[j];
    e.a[i] = -dy;
    e.b[i] = dx;
    e.c[i] = dy * x[j] - dx * y[j];
    e.bias[i] = (dy < 0 || (dy == 0 && dx > 0)) ? 0 : 1;
  }
  return e;
}
inline int64_t pixel_center(int32_t pixel) { return (int64_t(pixel) << kSubpixelBits) + kHalfPixel; }
inline bool covers(const Edges& e, int32_t px, int32_t py) {
  const int64_t x = pixel_center(px), y = pixel_center(py);
  int64_t inside = 0;
  for (int i = 0; i < 3; ++i) inside |= e.a[i] * x + e.b[i] * y + e.c[i] - e.bias[i];
  return inside >= 0;
}

// Range of pixels whose centres lie in [lo, hi] (fixed point); arithmetic shifts round toward -inf.
inline int32_t first_pixel(int32_t lo) { return (lo - kHalfPixel + kSubpixel - 1) >> kSubpixelBits; }
inline int32_t last_pixel(int32_t hi) { return (hi - kHalfPixel) >> kSubpixelBits; }

struct PixelBox {
  int32_t x0, y0, x1, y1;  // inclusive; empty when x0 > x1 or y0 > y1
};
inline PixelBox pixel_box(int32_t x0, int32_t x1, int32_t x2, int32_t y0, int32_t y1, int32_t y2, const Frame& frame) {
  const int32_t min_x = std::min(x0, std::min(x1, x2)), max_x = std::max(x0, std::max(x1, x2));
  const int32_t min_y = std::min(y0, std::min(y1, y2)), max_y = std::max(y0, std::max(y1, y2));
  return {std::max(first_pixel(min_x), 0), std::max(first_pixel(min_y), 0),
          std::min(last_pixel(max_x), int32_t(frame.width) - 1),
          std::min(last_pixel(max_y), int32_t(frame.height) - 1)};
}

// Per-vertex results of the vertex stage.
struct VertexData {
  std::vector<float> normals;        // 3 per vertex, area-weighted sums (not normalized)
  std::vector<float> clip;           // 4 per vertex
  std::vector<ScreenVertex> screen;  // valid when the outcode has no kClipMask bit
  std::vector<uint32_t> color;       // shaded RGB
  std::vector<uint8_t> outcode;
};

// vertex_stage.cpp
// Sums each face's cross product (2 x area x unit normal) into those of its corners in [begin, end),
// in face order: any split of the vertex range gives the same bits. `normals` must hold 3 per vertex.
// Throws pms::Error for an index out of range (the first such face, whatever the range).
void accumulate_normals(const RenderMesh& mesh, size_t begin, size_t end, std::vector<float>& normals);
// The same check without the normals, for a frame that is not shaded.
void check_indices(const RenderMesh& mesh);
// Shades the vertices only when options.shade (data.normals is then read, else data.color is left as is).
void transform_vertices(const RenderMesh& mesh, const ViewParams& view, const Frame& frame,
                        const RenderOptions& options, size_t begin, size_t end, VertexData& data);

// clip.cpp
struct ClipVertex {
  float c[4];    // clip coordinates
  float rgb[3];  // shaded colour, 0..255
};
// Clips the convex polygon poly[0, count) in place against the near plane (when `planes` has kOutNear)
// and the 4 guard planes (kOutGuard); returns the new vertex count (< 3: nothing left).
int clip_polygon(ClipVertex poly[kMaxPolygon], int count, uint8_t planes, const Frame& frame);

// binning.cpp
// Sets up faces [begin, end): culls, clips, snaps, drops triangles that cover no pixel centre, puts the
// rest in `tris` (in face order) with their tile in `tri_tile` (kNone when they touch several), and counts
// them per tile in tile_counts[tiles_x * tiles_y].
void setup_faces(const RenderMesh& mesh, const VertexData& data, const Frame& frame, size_t begin, size_t end,
                 std::vector<Tri>& tris, std::vector<uint32_t>& tri_tile, uint32_t* tile_counts);
// Writes the index of each triangle into every tile it touches: entries[cursor[tile]++].
void bin_triangles(const std::vector<Tri>& tris, const std::vector<uint32_t>& tri_tile, const Frame& frame,
                   uint32_t* cursor, uint32_t* entries);

// raster_tile.cpp
struct Target {
  uint8_t* rgb;  // nullptr: depth and face ids only
  float* depth;
  uint32_t* face_id;
  uint8_t background[3];
};
// Clears tile `tile` and draws triangles tris[entries[i]] for i in [begin, end) in that order (the order
// breaks depth ties: the first drawn keeps the pixel).
void clear_tile(const Frame& frame, uint32_t tile, const Target& target);
void raster_tile(const Frame& frame, uint32_t tile, const Tri* tris, const uint32_t* entries, size_t begin, size_t end,
                 const Target& target);

// renderer.cpp: fn(i) for i in [0, count) on up to `threads` threads; which thread runs which i must not
// matter to the result.
void parallel_for(unsigned threads, size_t count, const std::function<void(size_t)>& fn);

}  // namespace pms::render_detail
