// E10's transmission sizes (gueziec et al. 1999, "coupling with a geometry-compression method"): each
// level of a multilevel mesh in the compressed form against the binary and ASCII forms and gzip -9 of
// them, and against meshoptimizer's codecs on the same grid (docs/internals.md, "Progressive multilevel
// meshes").
#pragma once
#include <cstdint>
#include <nlohmann/json_fwd.hpp>

#include "multilevel/codec.h"
#include "multilevel/mesh.h"

namespace pms::bench {

// Bytes over every level (each level on its own, as it travels), and the compressed form's bits by part.
struct MultilevelSizes {
  uint64_t compressed = 0, binary = 0, binary_gzip = 0, ascii = 0, ascii_gzip = 0;
  uint64_t vertex_bits = 0, triangle_bits = 0;  // compressed: positions and attributes; connectivity + representatives
  uint64_t meshopt_vertex = 0, meshopt_index = 0;  // meshoptimizer's vertex and index-sequence codecs, per level
  CompressedLevelBits parts;  // the compressed form's bits by part, over every level
  double decode_ms = 0;       // decoding every compressed level through the loader: each level's fastest of a few
};

// `per_level` gets one object per level, coarsest first.
MultilevelSizes multilevel_sizes(const MultilevelMesh& mesh, uint32_t position_bits, nlohmann::json& per_level);

}  // namespace pms::bench
