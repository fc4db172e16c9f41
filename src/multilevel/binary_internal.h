// The binary multilevel form's HEAD and LEVL records (docs/multilevel-format.md), shared by the file's
// reader and writer and by the progressive loader, which takes the same records one at a time. Not public.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "multilevel/mesh.h"

namespace pms::multilevel_binary {

constexpr uint32_t kHasNormals = 1, kHasColors = 2, kHasTexcoords = 4;
// Every LEVL carries its LOD's secondary array after its representatives (MultilevelMesh::changed), and
// HEAD's changed_count totals their entries.
constexpr uint32_t kHasChanged = 8;

struct HeadSection {
  uint32_t level_count, dimension, flags, vertex_count, triangle_count, representative_count, changed_count, reserved;
};
static_assert(sizeof(HeadSection) == 32);

// The first 4 words of a LEVL section.
struct LevelHeader {
  uint32_t level, vertices, triangles, representatives;
};
static_assert(sizeof(LevelHeader) == 16);

// The compressed form's head (docs/multilevel-format.md, "Compressed levels"): HEAD, then the grid every
// level's positions are quantized on, and the bits of the texture coordinates' grid (0 without them).
struct CompressedHead {
  HeadSection head;
  uint32_t position_bits;
  float min[3], max[3];
  uint32_t texcoord_bits;
};
static_assert(sizeof(CompressedHead) == 64);

// After the compressed head when HEAD flags texture coordinates: the box of their grid.
struct TexcoordBox {
  float min[2], max[2];
};
static_assert(sizeof(TexcoordBox) == 16);

// The HEAD section of a (validated) mesh.
HeadSection head_section(const MultilevelMesh& mesh);

// A LEVL section from its parts, in the section's order; `changed` (with kHasChanged) after the
// representatives: its entry count, vertices, positions, normals, colours.
std::vector<uint8_t> level_section_bytes(const LevelHeader& header, std::span<const float> positions,
                                         std::span<const float> normals, std::span<const uint8_t> colors,
                                         std::span<const float> texcoords, std::span<const uint32_t> triangles,
                                         std::span<const uint32_t> representatives,
                                         const ChangedVertices* changed = nullptr);

}  // namespace pms::multilevel_binary
