// The binary multilevel form's HEAD and LEVL records (docs/multilevel-format.md), shared by the file's
// reader and writer and by the progressive loader, which takes the same records one at a time. Not public.
#pragma once
#include <cstdint>

namespace pms::multilevel_binary {

constexpr uint32_t kHasNormals = 1, kHasColors = 2;

struct HeadSection {
  uint32_t level_count, dimension, flags, vertex_count, triangle_count, representative_count, reserved[2];
};
static_assert(sizeof(HeadSection) == 32);

// The first 4 words of a LEVL section.
struct LevelHeader {
  uint32_t level, vertices, triangles, representatives;
};
static_assert(sizeof(LevelHeader) == 16);

}  // namespace pms::multilevel_binary
