// Compressed multilevel levels (gueziec et al. 1999, "coupling with a geometry-compression method";
// docs/multilevel-format.md, "Compressed levels"): each level coded as a mesh against the levels before
// it, its vertices quantized on one grid, its triangles' corners as places among the vertices the mesh so
// far puts next to each other, its positions predicted from their decoded neighbours, every decision
// under an adaptive range coder (common/range_coder.h). The progressive loader decodes a level into the
// LEVL section it stands for, so both forms reach the structure through the same checks.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "multilevel/level_neighbours.h"
#include "multilevel/loader.h"
#include "multilevel/mesh.h"
#include "spm/position_grid.h"

namespace pms {

// Bits of one compressed level by what they carry (bench: bits per vertex and per triangle).
struct CompressedLevelBits {
  uint64_t header = 0;           // the counts and the code tables
  uint64_t representatives = 0;  // the (vertex, representative) pairs
  uint64_t vertices = 0;         // positions, normals, colours, texture coordinates
  uint64_t triangles = 0;        // connectivity
  uint64_t changed = 0;          // the secondary array of its LOD
  uint64_t total() const { return header + representatives + vertices + triangles + changed; }
};

// The compressed form's version, in the compressed head's HEAD `reserved` word (the binary form's is 0):
// a loader refuses a head of any other.
constexpr uint32_t kCompressedLevelsVersion = 2;

// Bits per axis of the texture coordinates' grid in the compressed form.
constexpr uint32_t kDefaultTexcoordBits = 16;

// `bits` per axis (1..24) over the box of every vertex (a 2D mesh's z axis is flat).
PositionGrid multilevel_grid(const MultilevelMesh& mesh, uint32_t bits);
// Likewise over the box of every vertex's texture coordinates (u, v; z unused).
PositionGrid multilevel_texcoord_grid(const MultilevelMesh& mesh, uint32_t bits);
// The mesh with every position and texture coordinate on those grids: what the compressed form delivers.
MultilevelMesh snapped_multilevel(const MultilevelMesh& mesh, uint32_t bits,
                                  uint32_t texcoord_bits = kDefaultTexcoordBits);

// The compressed form in the pieces a client loads: the 64-byte compressed head (80 bytes with texture
// coordinates: their grid's box follows), then each level coarsest first. `bits`, if given, gets each
// level's breakdown in the same order.
MultilevelParts multilevel_compressed_parts(const MultilevelMesh& mesh, uint32_t position_bits = kDefaultPositionBits,
                                            std::vector<CompressedLevelBits>* bits = nullptr,
                                            uint32_t texcoord_bits = kDefaultTexcoordBits);

// What decoding a level reads of what is already loaded (MultilevelLoader's state).
struct CompressedLevelContext {
  uint32_t level = 0, dimension = 3;
  bool normals = false, colors = false, texcoords = false;
  PositionGrid grid, texcoord_grid;                     // texcoord_grid: only when `texcoords`
  uint64_t mesh_vertices = 0;  // the head's total
  uint32_t vertices_loaded = 0;
  uint32_t vertices_left = 0, triangles_left = 0, representatives_left = 0;  // what the head's totals allow
  bool changed = false;       // the levels carry secondary arrays
  uint32_t changed_left = 0;  // their entries the head's total allows
};

// The LEVL section a compressed level stands for; adds what it loads to `state`. pms::Error "WHERE:
// compressed level L: what" for a level that is not one: truncated or longer than its stream, counts over
// what is left, values outside the grid or the mesh, representatives not below their vertex.
std::vector<uint8_t> decode_compressed_level(const std::string& where, std::span<const uint8_t> level,
                                             const CompressedLevelContext& context, CompressedLevelState& state);

}  // namespace pms
