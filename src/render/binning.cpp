// Triangle setup and binning into 64x64 screen tiles (the sort-middle scheme of tiled renderers; see
// Abrash 2009, "Rasterization on Larrabee"). Faces are processed in chunks of consecutive indices, each
// chunk keeps its triangles in face order, and tiles read the chunks in order: so every tile sees its
// triangles in face order whatever the number of threads, and depth ties resolve the same way.
//
// Most triangles of a dense mesh are smaller than a pixel; those that cover no pixel centre are dropped
// here, before they cost a record and a bin entry.
#include <cmath>

#include "render/raster_internal.h"
#include "spm/vertex_id.h"

namespace pms::render_detail {
namespace {

uint32_t pack_rgb(const float rgb[3]) {
  uint32_t packed = 0;
  for (int k = 0; k < 3; ++k) {
    const float value = std::min(rgb[k] + 0.5f, 255.0f);
    packed |= uint32_t(value > 0 ? value : 0) << (8 * k);
  }
  return packed;
}

class Emitter {
 public:
  Emitter(const Frame& frame, std::vector<Tri>& tris, std::vector<uint32_t>& tri_tile, uint32_t* tile_counts)
      : frame_(frame), tris_(tris), tri_tile_(tri_tile), tile_counts_(tile_counts) {}

  [[gnu::always_inline]] void emit(const ScreenVertex& v0, const ScreenVertex& v1, const ScreenVertex& v2, uint32_t c0,
                                   uint32_t c1, uint32_t c2, uint32_t face) {
    // The pixel box first: most faces of a dense mesh end here, before any multiplication.
    const PixelBox box = pixel_box(v0.x, v1.x, v2.x, v0.y, v1.y, v2.y, frame_);
    if (box.x0 > box.x1 || box.y0 > box.y1) return;
    const int64_t area =
        (int64_t(v1.x) - v0.x) * (int64_t(v2.y) - v0.y) - (int64_t(v1.y) - v0.y) * (int64_t(v2.x) - v0.x);
    if (area == 0) return;  // degenerate after snapping: covers nothing
    // Both orientations are drawn; swapping two corners makes the edge functions positive inside.
    const bool flip = area < 0;
    const ScreenVertex& a = v0;
    const ScreenVertex& b = flip ? v2 : v1;
    const ScreenVertex& c = flip ? v1 : v2;
    const int32_t x[3] = {a.x, b.x, c.x}, y[3] = {a.y, b.y, c.y};
    if (box.x0 == box.x1 && box.y0 == box.y1 && !covers(edge_setup(x, y), box.x0, box.y0)) return;
    tris_.push_back({{a.x, b.x, c.x},
                     {a.y, b.y, c.y},
                     {a.z, b.z, c.z},
                     {a.inv_w, b.inv_w, c.inv_w},
                     {c0, flip ? c2 : c1, flip ? c1 : c2},
                     face});
    const int32_t tx0 = box.x0 >> kTileBits, tx1 = box.x1 >> kTileBits;
    const int32_t ty0 = box.y0 >> kTileBits, ty1 = box.y1 >> kTileBits;
    // Most triangles touch one tile: remember it, so the binning pass need not read the record again.
    tri_tile_.push_back(tx0 == tx1 && ty0 == ty1 ? uint32_t(ty0) * frame_.tiles_x + uint32_t(tx0) : kNone);
    for (int32_t ty = ty0; ty <= ty1; ++ty)
      for (int32_t tx = tx0; tx <= tx1; ++tx) ++tile_counts_[ty * frame_.tiles_x + tx];
  }

 private:
  const Frame& frame_;
  std::vector<Tri>& tris_;
  std::vector<uint32_t>& tri_tile_;
  uint32_t* tile_counts_;
};

void unpack_rgb(uint32_t packed, float rgb[3]) {
  for (int k = 0; k < 3; ++k) rgb[k] = float((packed >> (8 * k)) & 255);
}

// The rare face that crosses the near plane or the guard band: clip in clip space, then fan-triangulate
// the convex polygon (the fan's inner diagonals are shared, so the fill rule covers them once).
void emit_clipped(Emitter& emitter, const VertexData& data, const uint32_t corner[3], uint8_t planes,
                  const Frame& frame, uint32_t face) {
  ClipVertex poly[kMaxPolygon];
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 4; ++k) poly[i].c[k] = data.clip[4 * size_t(corner[i]) + k];
    unpack_rgb(data.color[corner[i]], poly[i].rgb);
  }
  const int count = clip_polygon(poly, 3, planes, frame);
  if (count < 3) return;
  ScreenVertex screen[kMaxPolygon];
  uint32_t color[kMaxPolygon];
  for (int i = 0; i < count; ++i) {
    screen[i] = project(poly[i].c, frame);
    color[i] = pack_rgb(poly[i].rgb);
  }
  for (int i = 1; i + 1 < count; ++i)
    emitter.emit(screen[0], screen[i], screen[i + 1], color[0], color[i], color[i + 1], face);
}

}  // namespace

void setup_faces(const RenderMesh& mesh, const VertexData& data, const Frame& frame, size_t begin, size_t end,
                 std::vector<Tri>& tris, std::vector<uint32_t>& tri_tile, uint32_t* tile_counts) {
  tris.clear();
  tri_tile.clear();
  Emitter emitter(frame, tris, tri_tile, tile_counts);
  const uint32_t* index = mesh.indices.data();
  const uint8_t* code = data.outcode.data();
  const ScreenVertex* screen = data.screen.data();
  const uint32_t* color = data.color.data();
  for (size_t f = begin; f < end; ++f) {
    const uint32_t* corner = index + 3 * f;
    const uint8_t c0 = code[corner[0]], c1 = code[corner[1]], c2 = code[corner[2]];
    if ((c0 & c1 & c2 & kCullMask) || ((c0 | c1 | c2) & kOutInvalid)) continue;
    const uint8_t any = c0 | c1 | c2;
    if (any & kClipMask) {
      emit_clipped(emitter, data, corner, any & kClipMask, frame, uint32_t(f));
      continue;
    }
    emitter.emit(screen[corner[0]], screen[corner[1]], screen[corner[2]], color[corner[0]], color[corner[1]],
                 color[corner[2]], uint32_t(f));
  }
}

void bin_triangles(const std::vector<Tri>& tris, const std::vector<uint32_t>& tri_tile, const Frame& frame,
                   uint32_t* cursor, uint32_t* entries) {
  for (uint32_t i = 0; i < tris.size(); ++i) {
    if (tri_tile[i] != kNone) {
      entries[cursor[tri_tile[i]]++] = i;
      continue;
    }
    const Tri& t = tris[i];
    const PixelBox box = pixel_box(t.x[0], t.x[1], t.x[2], t.y[0], t.y[1], t.y[2], frame);
    for (int32_t ty = box.y0 >> kTileBits; ty <= box.y1 >> kTileBits; ++ty)
      for (int32_t tx = box.x0 >> kTileBits; tx <= box.x1 >> kTileBits; ++tx)
        entries[cursor[ty * frame.tiles_x + tx]++] = i;
  }
}

}  // namespace pms::render_detail
