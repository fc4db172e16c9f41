// In-memory triangle mesh shared by importers, cleaning, the builder and exporters.
// Flat arrays (meshoptimizer style): one allocation per attribute, triangles as index triples.
#pragma once
#include <array>
#include <span>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/progress.h"

namespace pms {

struct Mesh {
  std::vector<float> positions;   // x y z per vertex
  std::vector<float> normals;     // x y z per vertex, or empty when the input had none
  std::vector<uint8_t> colors;    // r g b a per vertex, or empty when the input had none
  std::vector<float> texcoords;   // u v per vertex, or empty when the input had none
  std::vector<uint32_t> indices;  // 3 per triangle, counter-clockwise seen from outside

  size_t vertex_count() const { return positions.size() / 3; }
  size_t face_count() const { return indices.size() / 3; }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_texcoords() const { return !texcoords.empty(); }
};

// What clean_mesh() changed; every count is reported to the user.
struct CleanReport {
  size_t welded_vertices = 0;        // vertices merged into an exactly coincident one
  size_t unreferenced_vertices = 0;  // vertices no face used, dropped
  size_t degenerate_faces = 0;       // faces with a repeated corner (after welding) or zero area
  size_t duplicate_faces = 0;        // faces with the same corner set as an earlier face
  size_t nonmanifold_edges = 0;      // edges with more than two faces (or inconsistent orientation) cut apart
  size_t nonmanifold_vertices = 0;   // vertices whose faces form several fans, split into copies
  size_t split_vertex_copies = 0;    // new vertices created by the two repairs above
  size_t flipped_faces = 0;          // faces reoriented to agree with their neighbours
  size_t inside_out_components = 0;  // closed components whose winding (and normals) were reversed
  size_t inside_out_faces = 0;       // their faces
};

// Loads PLY (ascii/binary), OBJ, OFF, STL, glTF/GLB and anything else assimp reads; a trailing
// .gz or .xz is decompressed in memory. Polygons are fan-triangulated. Throws pms::Error
// ("PATH: problem") for unreadable, truncated or inconsistent files.
Mesh load_mesh(const std::string& path, const ProgressFn& progress = {});

// Same, from bytes already in memory; `name` is used for the format (extension) and in errors.
Mesh load_mesh_from_memory(const std::string& name, const std::vector<uint8_t>& bytes);

// Writes PLY (binary little-endian by default), with normals/colors/texture coordinates (`s t`) when present.
void save_ply(const Mesh& mesh, const std::string& path, bool binary = true);

// Welds exactly coincident vertices, drops unreferenced vertices, degenerate and duplicate faces,
// and cuts non-manifold edges/vertices so the result is an oriented 2-manifold (boundaries allowed) whose
// closed components face outward.
CleanReport clean_mesh(Mesh& mesh);

// The triangles of `indices` over `positions` as their corners' positions, each rotated to start at its
// smallest corner, sorted; triangles with a repeated corner (a renderer's free slot) are left out. Two
// meshes draw the same triangles exactly when these are equal, however their vertices are numbered.
using PositionedTriangle = std::array<float, 9>;
std::vector<PositionedTriangle> positioned_triangles(std::span<const float> positions,
                                                     std::span<const uint32_t> indices);

}  // namespace pms
