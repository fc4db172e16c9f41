#include "client/mesh_buffers.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <span>

namespace pms::client {
namespace {

// Collects the elements that changed into runs, merging runs closer than kMergeGap.
class ChangeRuns {
 public:
  explicit ChangeRuns(std::vector<BufferRange>& out) : out_(out) { out_.clear(); }
  void mark(uint32_t element) { mark_up_to(element, element + 1); }
  // [first, end), after every element marked so far.
  void mark_up_to(uint32_t first, uint32_t end) {
    if (end <= first) return;
    if (!out_.empty() && first < out_.back().first + out_.back().count + MeshBuffers::kMergeGap) {
      out_.back().count = end - out_.back().first;
    } else {
      out_.push_back({first, end - first});
    }
  }

 private:
  std::vector<BufferRange>& out_;
};

// The bits of `value`: floats compare as stored, so that -0 against +0 (or a NaN) counts as a change.
inline uint32_t bits(float value) {
  uint32_t out;
  std::memcpy(&out, &value, sizeof out);
  return out;
}
inline uint32_t bits(uint32_t value) { return value; }
inline uint32_t bits(uint8_t value) { return value; }

// Stores the N values of `value` at element `i` of `array` (N per element); true when they differ. Element
// by element, not memcmp: N is a handful and a call into libc per vertex costs more than the compare.
template <size_t N, class T>
bool store(std::vector<T>& array, size_t i, const T* value) {
  T* at = &array[N * i];
  uint32_t differ = 0;
  for (size_t k = 0; k < N; ++k) differ |= bits(at[k]) ^ bits(value[k]);
  if (differ == 0) return false;
  for (size_t k = 0; k < N; ++k) at[k] = value[k];
  return true;
}

// Adds each live triangle's area-weighted normal to its corners' entries of `out`.
void accumulate_face_normals(std::span<const float> positions, std::span<const uint32_t> indices, std::vector<float>& out) {
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    if (a == b || b == c || a == c) continue;  // a free slot, or degenerate
    const float* p = &positions[3 * size_t(a)];
    const float* q = &positions[3 * size_t(b)];
    const float* r = &positions[3 * size_t(c)];
    const float u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const float v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const float n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    for (uint32_t corner : {a, b, c})
      for (int k = 0; k < 3; ++k) out[3 * size_t(corner) + k] += n[k];
  }
}

void normalize_at(std::vector<float>& out, size_t i) {
  const float length = std::sqrt(out[i] * out[i] + out[i + 1] * out[i + 1] + out[i + 2] * out[i + 2]);
  if (length > 0)
    for (int k = 0; k < 3; ++k) out[i + k] /= length;
}

// Area-weighted vertex normals of `indices` over `positions`, unit length (zero for a vertex no live
// triangle uses).
void face_normals(std::span<const float> positions, std::span<const uint32_t> indices, std::vector<float>& out) {
  out.assign(positions.size(), 0.0f);
  accumulate_face_normals(positions, indices, out);
  for (size_t i = 0; i + 2 < out.size(); i += 3) normalize_at(out, i);
}

// face_normals() for the `active` vertices only: the others' entries are left as they were, so the work
// follows the mesh, not every slot the hierarchy ever held.
void active_face_normals(std::span<const uint32_t> active, std::span<const float> positions,
                         std::span<const uint32_t> indices, std::vector<float>& out) {
  out.resize(positions.size(), 0.0f);
  for (uint32_t v : active) std::fill_n(&out[3 * size_t(v)], 3, 0.0f);
  accumulate_face_normals(positions, indices, out);
  for (uint32_t v : active) normalize_at(out, 3 * size_t(v));
}

// The arrays' sizes before they grew: from there on everything counts as changed (a renderer reallocates
// a buffer that grew, and uploads it whole).
struct Grown {
  uint32_t vertices, triangles;
};

Grown grow(MeshBuffers& buffers, size_t vertices, size_t triangles) {
  const Grown before{buffers.vertex_count(), buffers.triangle_count()};
  if (vertices > before.vertices) {
    buffers.positions.resize(3 * vertices, 0.0f);
    buffers.normals.resize(3 * vertices, 0.0f);
    buffers.colors.resize(4 * vertices, 255);
  }
  if (triangles > before.triangles) buffers.indices.resize(3 * triangles, 0);
  return before;
}

}  // namespace

void update_buffers(const SelectiveRefinement& refinement, MeshBuffers& buffers) {
  const SelectiveMesh& mesh = refinement.mesh();
  const VertexHierarchy& h = mesh.hierarchy();
  const Geomorphs& morphs = refinement.geomorphs();
  const MeshBuffers::Source source{mesh.changes(), h.size(), mesh.face_capacity(), morphs.morphing() == 0};
  if (source.at_rest && source == buffers.source) {
    buffers.changed_vertices.clear();
    buffers.changed_triangles.clear();
    ++buffers.updates;
    return;
  }
  buffers.source = source;
  const Grown grown = grow(buffers, h.size(), mesh.face_capacity());
  ChangeRuns triangles(buffers.changed_triangles);
  static constexpr uint32_t kFree[3] = {0, 0, 0};
  for (uint32_t f = 0; f < grown.triangles; ++f)
    if (store<3>(buffers.indices, f, mesh.face_alive(f) ? mesh.face(f) : kFree)) triangles.mark(f);
  for (uint32_t f = grown.triangles; f < mesh.face_capacity(); ++f)
    store<3>(buffers.indices, f, mesh.face_alive(f) ? mesh.face(f) : kFree);
  triangles.mark_up_to(grown.triangles, mesh.face_capacity());
  static constexpr uint8_t kWhite[4] = {255, 255, 255, 255};
  // Which blocks of kMergeGap slots hold a vertex whose entries changed, a bit each: runs come out in order
  // without a sort and the work follows the mesh, not every slot the hierarchy ever received. A run covers
  // whole blocks (a few unchanged entries, which the merge gap allows).
  constexpr uint32_t kBlock = MeshBuffers::kMergeGap;
  std::vector<uint64_t>& blocks = buffers.changed_blocks;
  blocks.assign((h.size() + 64 * kBlock - 1) / (64 * kBlock), 0);
  auto changed = [&](uint32_t v) { blocks[v / (64 * kBlock)] |= uint64_t(1) << (v / kBlock % 64); };
  const std::span<const uint32_t> active = mesh.active_vertices();
  for (uint32_t v : active) {
    bool moved = store<3>(buffers.positions, v, morphs.enabled() ? morphs.shown(h, v) : h.position(v));
    moved |= store<4>(buffers.colors, v, h.has_colors() ? h.color(v) : kWhite);
    if (moved) changed(v);
  }
  // Without the model's normals, the faces' around each vertex, from the positions just stored (a
  // vertex's normal changes with any face around it).
  if (!h.has_normals()) active_face_normals(active, buffers.positions, buffers.indices, buffers.computed_normals);
  for (uint32_t v : active)
    if (store<3>(buffers.normals, v, h.has_normals() ? h.normal(v) : &buffers.computed_normals[3 * size_t(v)]))
      changed(v);
  ChangeRuns vertices(buffers.changed_vertices);
  for (size_t word = 0; word < blocks.size(); ++word)
    for (uint64_t mask = blocks[word]; mask != 0; mask &= mask - 1) {
      const uint32_t first = uint32_t((word * 64 + uint32_t(std::countr_zero(mask))) * kBlock);
      if (first >= grown.vertices) break;
      vertices.mark_up_to(first, std::min(first + kBlock, grown.vertices));
    }
  vertices.mark_up_to(grown.vertices, h.size());
  ++buffers.updates;
}

void update_buffers(const Mesh& mesh, MeshBuffers& buffers) {
  buffers.source = {};  // read from a Mesh: the next update from a refinement reads everything
  const size_t vertex_count = mesh.positions.size() / 3, triangle_count = mesh.indices.size() / 3;
  const Grown grown = grow(buffers, vertex_count, triangle_count);
  ChangeRuns triangles(buffers.changed_triangles);
  static constexpr uint32_t kFree[3] = {0, 0, 0};
  for (size_t t = 0; t < buffers.indices.size() / 3; ++t)
    if (store<3>(buffers.indices, t, t < triangle_count ? &mesh.indices[3 * t] : kFree) && t < grown.triangles)
      triangles.mark(uint32_t(t));
  triangles.mark_up_to(grown.triangles, uint32_t(triangle_count));
  const bool has_normals = mesh.normals.size() == mesh.positions.size();
  if (!has_normals) face_normals(mesh.positions, mesh.indices, buffers.computed_normals);
  const std::vector<float>& normals = has_normals ? mesh.normals : buffers.computed_normals;
  static constexpr uint8_t kWhite[4] = {255, 255, 255, 255};
  const bool has_colors = mesh.colors.size() == 4 * vertex_count;
  ChangeRuns vertices(buffers.changed_vertices);
  for (size_t v = 0; v < vertex_count; ++v) {
    bool changed = store<3>(buffers.positions, v, &mesh.positions[3 * v]);
    changed |= store<3>(buffers.normals, v, &normals[3 * v]);
    changed |= store<4>(buffers.colors, v, has_colors ? &mesh.colors[4 * v] : kWhite);
    if (changed && v < grown.vertices) vertices.mark(uint32_t(v));
  }
  vertices.mark_up_to(grown.vertices, uint32_t(vertex_count));
  ++buffers.updates;
}

}  // namespace pms::client
