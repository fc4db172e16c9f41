// Progressive loading of a multilevel mesh (multilevel/loader.h): the paper's addLevel on the binary
// form's records, with every check a level needs before its LOD is used.
#include "multilevel/loader.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/error.h"
#include "multilevel/binary_internal.h"
#include "multilevel/codec.h"

namespace pms {
namespace {

using multilevel_binary::CompressedHead;
using multilevel_binary::HeadSection;
using multilevel_binary::kHasChanged;
using multilevel_binary::kHasColors;
using multilevel_binary::kHasNormals;
using multilevel_binary::kHasTexcoords;
using multilevel_binary::level_section_bytes;
using multilevel_binary::LevelHeader;
using multilevel_binary::TexcoordBox;

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;

std::string str(uint64_t v) { return std::to_string(v); }

template <typename T>
void append_bytes(std::vector<uint8_t>& out, const T* data, size_t count) {
  if (count == 0) return;  // data() may be null
  const size_t at = out.size();
  out.resize(at + count * sizeof(T));
  std::memcpy(out.data() + at, data, count * sizeof(T));
}

// One level's LEVL section: its header, vertices (positions, normals, colours, texture coordinates), triangles, then
// the representatives it carries (level_representatives: what its triangles state, in the ASCII form's order, then its
// own vertices' geomorph representatives).
std::vector<uint8_t> level_section(const MultilevelMesh& m, uint32_t level, std::vector<uint8_t>& stated) {
  const uint32_t v_end = m.vertex_count[level], t_end = m.triangle_count[level];
  const uint32_t v_begin = v_end - m.level_vertices(level), t_begin = t_end - m.level_triangles(level);
  const std::vector<uint32_t> reps = level_representatives(m, level, stated);
  const LevelHeader h{level, v_end - v_begin, t_end - t_begin, uint32_t(reps.size() / 2)};
  const auto part = [](const auto& array, size_t begin, size_t count) {
    return array.empty() ? std::span(array.data(), size_t(0)) : std::span(array.data() + begin, count);
  };
  const size_t d = m.dimension;
  return level_section_bytes(h, part(m.positions, v_begin * d, h.vertices * d),
                             part(m.normals, v_begin * 3, h.vertices * 3), part(m.colors, v_begin * 4, h.vertices * 4),
                             part(m.texcoords, v_begin * 2, h.vertices * 2),
                             part(m.triangles, t_begin * 3, h.triangles * 3), reps,
                             m.changed.empty() ? nullptr : &m.changed[level]);
}

// A grid of the compressed head: 1 to 24 bits over a box of `d` finite axes (those past d stay flat).
PositionGrid head_grid(const std::string& where, uint32_t bits, const float* min, const float* max, int d,
                       const char* bits_name, const char* box_name) {
  if (bits < 1 || bits > 24) fail(where, "compressed head: " + str(bits) + " " + bits_name + " (1 to 24)");
  PositionGrid grid;
  grid.bits = bits;
  for (int k = 0; k < d; ++k) {
    if (!std::isfinite(min[k]) || !std::isfinite(max[k]) || min[k] > max[k])
      fail(where, std::string("compressed head: ") + box_name + " is not a box");
    grid.min[k] = min[k], grid.max[k] = max[k];
  }
  return grid;
}

// Appends `count` elements of `out`'s type from `p` and moves `p` past them.
template <typename T>
void take(std::vector<T>& out, const uint8_t*& p, uint64_t count) {
  if (count == 0) return;  // data() may be null
  const size_t at = out.size();
  out.resize(at + count);
  std::memcpy(out.data() + at, p, count * sizeof(T));
  p += count * sizeof(T);
}

}  // namespace

HeadSection multilevel_binary::head_section(const MultilevelMesh& m) {
  return {m.level_count(),
          m.dimension,
          (m.normals.empty() ? 0 : kHasNormals) | (m.colors.empty() ? 0 : kHasColors) |
              (m.texcoords.empty() ? 0 : kHasTexcoords) | (m.changed.empty() ? 0 : kHasChanged),
          m.vertices(),
          m.faces(),
          uint32_t(m.stored_representatives()),
          uint32_t(m.changed_vertices()),
          0};
}

std::vector<uint8_t> multilevel_binary::level_section_bytes(const LevelHeader& h, std::span<const float> positions,
                                                            std::span<const float> normals,
                                                            std::span<const uint8_t> colors,
                                                            std::span<const float> texcoords,
                                                            std::span<const uint32_t> triangles,
                                                            std::span<const uint32_t> representatives,
                                                            const ChangedVertices* changed) {
  std::vector<uint8_t> out;
  out.reserve(sizeof h +
              4 * (positions.size() + normals.size() + texcoords.size() + triangles.size() + representatives.size()) +
              colors.size());
  append_bytes(out, &h, 1);
  append_bytes(out, positions.data(), positions.size());
  append_bytes(out, normals.data(), normals.size());
  append_bytes(out, colors.data(), colors.size());
  append_bytes(out, texcoords.data(), texcoords.size());
  append_bytes(out, triangles.data(), triangles.size());
  append_bytes(out, representatives.data(), representatives.size());
  if (changed) {
    const auto count = uint32_t(changed->size());
    append_bytes(out, &count, 1);
    append_bytes(out, changed->vertex.data(), changed->vertex.size());
    append_bytes(out, changed->positions.data(), changed->positions.size());
    append_bytes(out, changed->normals.data(), changed->normals.size());
    append_bytes(out, changed->colors.data(), changed->colors.size());
  }
  return out;
}

MultilevelParts multilevel_parts(const MultilevelMesh& m) {
  validate_multilevel("", m);
  MultilevelParts parts;
  const HeadSection head = multilevel_binary::head_section(m);
  append_bytes(parts.head, &head, 1);
  std::vector<uint8_t> stated(m.vertices(), 0);
  for (uint32_t level = m.level_count(); level-- > 0;) parts.levels.push_back(level_section(m, level, stated));
  return parts;
}

MultilevelLoader::MultilevelLoader(const std::string& where, std::span<const uint8_t> head,
                                   const MultilevelLimits& limits, MultilevelForm form)
    : form_(form) {
  HeadSection compressed_head;
  if (form == MultilevelForm::compressed) {
    read_compressed_head(where, head);
    // Its HEAD carries the compressed form's version where the binary form's has 0.
    std::memcpy(&compressed_head, head.data(), sizeof compressed_head);
    compressed_head.reserved = 0;
    head = {reinterpret_cast<const uint8_t*>(&compressed_head), sizeof compressed_head};
  }
  if (head.size() != sizeof(HeadSection))
    fail(where, "section HEAD: " + str(head.size()) + " bytes (" + str(sizeof(HeadSection)) + " expected)");
  HeadSection h;
  std::memcpy(&h, head.data(), sizeof h);
  if (h.level_count == 0 || h.level_count > limits.max_levels)
    fail(where, "section HEAD: " + str(h.level_count) + " levels (1 to " + str(limits.max_levels) + ")");
  if (h.dimension < 2 || h.dimension > 3) fail(where, "section HEAD: dimension " + str(h.dimension));
  if (h.flags & ~(kHasNormals | kHasColors | kHasTexcoords | kHasChanged)) fail(where, "section HEAD: unknown flags");
  if (h.vertex_count > 0x7FFFFFFFu || h.triangle_count > 0x7FFFFFFFu || h.representative_count > h.vertex_count)
    fail(where, "section HEAD: more than 2^31 vertices or triangles, or more representatives than vertices");
  // Each LOD changes at most its own vertices: the entries are bounded by the levels times the vertices.
  if ((h.changed_count != 0 && !(h.flags & kHasChanged)) || h.reserved != 0 ||
      h.changed_count > uint64_t(h.vertex_count) * (h.level_count - 1))
    fail(where, "section HEAD: secondary array entries without the flag, more than the levels allow, or reserved "
                "bits set");
  const uint64_t per_vertex = 4 * (h.dimension + (h.flags & kHasNormals ? 3 : 0) + (h.flags & kHasTexcoords ? 2 : 0)) +
                              (h.flags & kHasColors ? 4 : 0);
  const uint64_t per_change = 4 * (1 + h.dimension + (h.flags & kHasNormals ? 3 : 0)) + (h.flags & kHasColors ? 4 : 0);
  const uint64_t bytes = per_vertex * h.vertex_count + 12 * uint64_t(h.triangle_count) +
                         8 * uint64_t(h.representative_count) + per_change * h.changed_count;
  if (bytes > limits.max_file_bytes)
    fail(where, "section HEAD: a mesh of " + str(bytes) + " bytes, over the limit of " + str(limits.max_file_bytes));
  flags_ = h.flags;
  total_vertices_ = h.vertex_count;
  total_triangles_ = h.triangle_count;
  total_representatives_ = h.representative_count;
  total_changed_ = h.changed_count;
  if (h.flags & kHasChanged) mesh_.changed.resize(h.level_count);
  mesh_.dimension = h.dimension;
  mesh_.vertex_count.assign(h.level_count, 0);
  mesh_.triangle_count.assign(h.level_count, 0);
  mesh_.representative.assign(h.vertex_count, kNoRep);
  mesh_.positions.reserve(size_t(h.vertex_count) * h.dimension);
  mesh_.triangles.reserve(3 * size_t(h.triangle_count));
  resolved_.assign(h.vertex_count, 0);
}

// The grids are checked here; the HEAD the head starts with, by the constructor.
void MultilevelLoader::read_compressed_head(const std::string& where, std::span<const uint8_t> head) {
  CompressedHead h{};
  if (head.size() >= sizeof h) std::memcpy(&h, head.data(), sizeof h);
  if (head.size() >= sizeof h && h.head.reserved != kCompressedLevelsVersion)
    fail(where, "compressed head: version " + str(h.head.reserved) + " levels (this client decodes version " +
                    str(kCompressedLevelsVersion) + "); load the model again");
  const bool texcoords = h.head.flags & kHasTexcoords;
  const size_t expected = sizeof h + (texcoords ? sizeof(TexcoordBox) : 0);
  if (head.size() != expected)
    fail(where, "compressed head: " + str(head.size()) + " bytes (" + str(expected) + " expected)");
  grid_ = head_grid(where, h.position_bits, h.min, h.max, 3, "position bits", "the grid's box");
  if (!texcoords) {
    if (h.texcoord_bits != 0) fail(where, "compressed head: texture coordinate bits without texture coordinates");
    return;
  }
  TexcoordBox box;
  std::memcpy(&box, head.data() + sizeof h, sizeof box);
  texcoord_grid_ =
      head_grid(where, h.texcoord_bits, box.min, box.max, 2, "texture coordinate bits", "the texture coordinates' box");
}

void MultilevelLoader::add_level(const std::string& where, std::span<const uint8_t> section, uint64_t offset) {
  if (complete()) fail(where, "more LEVL sections than HEAD's " + str(level_count()) + " levels");
  if (form_ == MultilevelForm::plain) {
    add_plain_level(where, section, offset);
    return;
  }
  const CompressedLevelContext context{next_level(),
                                       mesh_.dimension,
                                       (flags_ & kHasNormals) != 0,
                                       (flags_ & kHasColors) != 0,
                                       (flags_ & kHasTexcoords) != 0,
                                       grid_,
                                       texcoord_grid_,
                                       total_vertices_,
                                       mesh_.vertices(),
                                       total_vertices_ - mesh_.vertices(),
                                       total_triangles_ - mesh_.faces(),
                                       total_representatives_ - representatives_,
                                       (flags_ & kHasChanged) != 0,
                                       total_changed_ - changed_};
  const std::vector<uint8_t> plain = decode_compressed_level(where, section, context, compressed_);
  add_plain_level(where, plain, offset);
  if (complete()) compressed_ = {};  // only later levels are coded against it
}

void MultilevelLoader::add_plain_level(const std::string& where, std::span<const uint8_t> section, uint64_t offset) {
  const uint32_t level = next_level();
  const std::string name = "offset " + str(offset) + ": section LEVL of level " + str(level);
  if (section.size() % 4 || section.size() < sizeof(LevelHeader))
    fail(where, name + ": " + str(section.size()) + " bytes, not whole words or too short for its header");
  LevelHeader h;
  std::memcpy(&h, section.data(), sizeof h);
  if (h.level != level) fail(where, name + ": says it is level " + str(h.level));
  const bool normals = flags_ & kHasNormals, colors = flags_ & kHasColors, texcoords = flags_ & kHasTexcoords;
  const uint64_t per_vertex = mesh_.dimension + (normals ? 3 : 0) + (colors ? 1 : 0) + (texcoords ? 2 : 0);
  uint64_t words = 4 + per_vertex * h.vertices + 3 * uint64_t(h.triangles) + 2 * uint64_t(h.representatives);
  uint32_t changed = 0;  // its secondary array's entries, counted in the word after the representatives
  if (flags_ & kHasChanged) {
    if (words >= section.size() / 4) fail(where, name + ": no count of its secondary array");
    std::memcpy(&changed, section.data() + 4 * words, 4);
    if (uint64_t(changed_) + changed > total_changed_)
      fail(where, name + ": more secondary array entries than HEAD's total");
    words += 1 + uint64_t(changed) * (1 + mesh_.dimension + (normals ? 3 : 0) + (colors ? 1 : 0));
  }
  if (words != section.size() / 4)
    fail(where, name + ": " + str(section.size() / 4) + " words but its counts need " + str(words));
  const uint32_t v_begin = mesh_.vertices(), t_begin = mesh_.faces();
  if (uint64_t(v_begin) + h.vertices > total_vertices_ || uint64_t(t_begin) + h.triangles > total_triangles_ ||
      uint64_t(representatives_) + h.representatives > total_representatives_)
    fail(where, name + ": more vertices, triangles or representatives than HEAD's totals");
  const uint8_t* p = section.data() + sizeof h;
  take(mesh_.positions, p, uint64_t(h.vertices) * mesh_.dimension);
  if (normals) take(mesh_.normals, p, uint64_t(h.vertices) * 3);
  if (colors) take(mesh_.colors, p, uint64_t(h.vertices) * 4);
  if (texcoords) take(mesh_.texcoords, p, uint64_t(h.vertices) * 2);
  take(mesh_.triangles, p, uint64_t(h.triangles) * 3);
  std::vector<uint32_t> pairs;
  take(pairs, p, uint64_t(h.representatives) * 2);
  for (size_t i = size_t(v_begin) * mesh_.dimension; i < mesh_.positions.size(); ++i)
    if (!std::isfinite(mesh_.positions[i])) fail(where, "a vertex position of level " + str(level) + " is not finite");
  for (size_t i = size_t(v_begin) * 3; i < mesh_.normals.size(); ++i)
    if (!std::isfinite(mesh_.normals[i])) fail(where, "a vertex normal of level " + str(level) + " is not finite");
  for (size_t i = size_t(v_begin) * 2; i < mesh_.texcoords.size(); ++i)
    if (!std::isfinite(mesh_.texcoords[i]))
      fail(where, "a vertex texture coordinate of level " + str(level) + " is not finite");
  take_representatives(where, pairs);
  const uint32_t n_l = v_begin + h.vertices;
  if (flags_ & kHasChanged) {
    p += 4;  // the count
    take_changed(where, level, n_l, changed, p);
  }
  for (uint32_t l = 0; l <= level; ++l) {
    mesh_.vertex_count[l] = n_l;
    mesh_.triangle_count[l] = t_begin + h.triangles;
  }
  check_level_triangles(where, t_begin, n_l);
  ++loaded_;
  if (!complete()) return;
  if (mesh_.vertices() != total_vertices_ || mesh_.faces() != total_triangles_ ||
      representatives_ != total_representatives_ || changed_ != total_changed_)
    fail(where, "section HEAD: its totals disagree with the LEVL sections");
  validate_multilevel(where, mesh_);
}

// Level `level`'s secondary array: vertices of its LOD (below n_l) in ascending order, finite values, none
// at level 0; what a LOD shows as soon as its level is in.
void MultilevelLoader::take_changed(const std::string& where, uint32_t level, uint32_t n_l, uint32_t count,
                                    const uint8_t*& p) {
  ChangedVertices& c = mesh_.changed[level];
  const std::string name = "the secondary array of level " + str(level);
  if (count > 0 && level == 0) fail(where, name + ": LOD 0 is the primary arrays");
  take(c.vertex, p, count);
  take(c.positions, p, uint64_t(count) * mesh_.dimension);
  if (flags_ & kHasNormals) take(c.normals, p, uint64_t(count) * 3);
  if (flags_ & kHasColors) take(c.colors, p, uint64_t(count) * 4);
  for (size_t i = 0; i < c.size(); ++i)
    if (c.vertex[i] >= n_l || (i > 0 && c.vertex[i] <= c.vertex[i - 1]))
      fail(where, name + ": vertex " + str(c.vertex[i]) + " is not in its LOD or not in ascending order");
  for (float x : c.positions)
    if (!std::isfinite(x)) fail(where, name + ": a position is not finite");
  for (float x : c.normals)
    if (!std::isfinite(x)) fail(where, name + ": a normal is not finite");
  changed_ += count;
}

void MultilevelLoader::take_representatives(const std::string& where, std::span<const uint32_t> pairs) {
  for (size_t k = 0; k < pairs.size(); k += 2) {
    const uint32_t v = pairs[k], r = pairs[k + 1];
    if (v >= total_vertices_)
      fail(where, "a representative of vertex " + str(v) + ", beyond the file's " + str(total_vertices_));
    if (r >= v) fail(where, "vertex " + str(v) + " has representative " + str(r) + ", which is not below it");
    if (mesh_.representative[v] != kNoRep) fail(where, "vertex " + str(v) + " has two representatives");
    mesh_.representative[v] = r;
    ++representatives_;
  }
}

// Every corner of the new level's triangles must reach a loaded vertex along its representatives. A chain
// that did once always will (loaded vertices stay, representatives never change), so each vertex is
// walked at most once over the whole load.
void MultilevelLoader::check_level_triangles(const std::string& where, uint32_t t_begin, uint32_t n_l) {
  const uint32_t level = next_level();
  for (uint32_t t = t_begin; t < mesh_.faces(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh_.triangles[3 * size_t(t) + k];
      if (v >= total_vertices_)
        fail(where, "triangle " + str(t) + " names vertex " + str(v) + " of " + str(total_vertices_));
      uint32_t u = v;
      while (u >= n_l && !resolved_[u]) {
        u = mesh_.representative[u];
        if (u == kNoRep)
          fail(where, "triangle " + str(t) + " of level " + str(level) + " names vertex " + str(v) +
                          ", which is missing from that level and has no representative in it");
      }
      for (uint32_t w = v; w >= n_l && !resolved_[w]; w = mesh_.representative[w]) resolved_[w] = 1;
    }
  }
}

}  // namespace pms
