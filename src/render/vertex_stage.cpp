// Per-vertex work, done once per vertex instead of once per corner: area-weighted normals of the mesh
// being drawn (so a coarse mesh looks coarse), the clip transform, outcodes, the snapped screen position
// and the Lambert-shaded colour (Gouraud: lit at the vertices, interpolated across the face).
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "common/error.h"
#include "render/raster_internal.h"

namespace pms::render_detail {

Frame make_frame(const ViewParams& view) {
  Frame frame;
  frame.width = view.camera.width;
  frame.height = view.camera.height;
  frame.half_width = 0.5f * float(frame.width);
  frame.half_height = 0.5f * float(frame.height);
  // NDC x = +-1 is the viewport edge; the guard band extends kGuardPixels beyond it on each side.
  frame.guard_x = 1.0f + kGuardPixels / frame.half_width;
  frame.guard_y = 1.0f + kGuardPixels / frame.half_height;
  frame.tiles_x = (frame.width + kTileSize - 1) / kTileSize;
  frame.tiles_y = (frame.height + kTileSize - 1) / kTileSize;
  return frame;
}

namespace {

[[noreturn]] void index_out_of_range(size_t face, size_t vertex_count) {
  fail("render", "face " + std::to_string(face) + " uses a vertex index out of range (" + std::to_string(vertex_count) +
                     " vertices)");
}

}  // namespace

void check_indices(const RenderMesh& mesh) {
  const size_t vertex_count = mesh.positions.size() / 3;
  for (size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= vertex_count) index_out_of_range(i / 3, vertex_count);
}

void accumulate_normals(const RenderMesh& mesh, size_t begin, size_t end, std::vector<float>& normals) {
  const size_t vertex_count = mesh.positions.size() / 3, face_count = mesh.indices.size() / 3;
  std::fill(normals.begin() + 3 * begin, normals.begin() + 3 * end, 0.0f);
  const float* p = mesh.positions.data();
  const uint32_t* index = mesh.indices.data();
  for (size_t f = 0; f < face_count; ++f) {
    const uint32_t i0 = index[3 * f], i1 = index[3 * f + 1], i2 = index[3 * f + 2];
    if (i0 >= vertex_count || i1 >= vertex_count || i2 >= vertex_count) index_out_of_range(f, vertex_count);
    const bool mine0 = i0 >= begin && i0 < end, mine1 = i1 >= begin && i1 < end, mine2 = i2 >= begin && i2 < end;
    if (!(mine0 || mine1 || mine2)) continue;
    const float* a = p + 3 * size_t(i0);
    const float* b = p + 3 * size_t(i1);
    const float* c = p + 3 * size_t(i2);
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    // Unnormalized cross product: its length is twice the area, which is the weight we want.
    const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    auto add = [&](uint32_t v) {
      for (int k = 0; k < 3; ++k) normals[3 * size_t(v) + k] += n[k];
    };
    if (mine0) add(i0);
    if (mine1) add(i1);
    if (mine2) add(i2);
  }
}

namespace {

// The unit direction the light shines along: options.light, or the headlight (the view direction).
std::array<float, 3> light_direction(const ViewParams& view, const RenderOptions& options) {
  const float* l = options.light;
  const float length = std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
  if (!(length > 0)) return {view.forward[0], view.forward[1], view.forward[2]};
  return {l[0] / length, l[1] / length, l[2] / length};
}

}  // namespace

void transform_vertices(const RenderMesh& mesh, const ViewParams& view, const Frame& frame,
                        const RenderOptions& options, size_t begin, size_t end, VertexData& data) {
  const float* m = view.view_projection.m;
  const std::array<float, 3> light = light_direction(view, options);
  const bool has_colors = !mesh.colors.empty();
  for (size_t v = begin; v < end; ++v) {
    const float* p = &mesh.positions[3 * v];
    float* clip = &data.clip[4 * v];
    for (int r = 0; r < 4; ++r) clip[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
    const uint8_t code = outcode(clip, frame);
    data.outcode[v] = code;
    data.screen[v] = code & (kClipMask | kOutInvalid) ? ScreenVertex{0, 0, 0, 0} : project(clip, frame);
    if (!options.shade) continue;

    // |cos| lights back faces like front faces, since open meshes show their inside through holes.
    const float* n = &data.normals[3 * v];
    const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    float cosine = length > 0 ? std::fabs(n[0] * light[0] + n[1] * light[1] + n[2] * light[2]) / length : 0.0f;
    cosine = std::min(cosine, 1.0f);
    const float intensity = options.ambient + (1.0f - options.ambient) * cosine;
    const uint8_t* base = has_colors ? &mesh.colors[4 * v] : options.surface;
    uint32_t packed = 0;
    for (int k = 0; k < 3; ++k) {
      const float value = std::min(float(base[k]) * intensity + 0.5f, 255.0f);
      packed |= uint32_t(value > 0 ? value : 0) << (8 * k);
    }
    data.color[v] = packed;
  }
}

}  // namespace pms::render_detail
