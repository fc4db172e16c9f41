// Deterministic generated meshes: test fixtures and the built-in demo terrain.
#pragma once
#include <cstdint>

#include "io/mesh.h"

namespace pms {

Mesh make_sphere(int rings, int segments);                   // closed, genus 0 (UV sphere, poles welded)
Mesh make_torus(int rings, int segments, float R, float r);  // closed, genus 1
Mesh make_grid(int nx, int ny);                              // open square with one boundary loop
// Two tetrahedra sharing a vertex, plus a "book" of three triangles sharing one edge and a duplicate
// face: clean_mesh() must turn it into an oriented manifold.
Mesh make_nonmanifold_fixture();
// What the terrain's vertices carry besides positions: nothing (the meshes the byte-comparing tests
// and benches build), or colours of land seen from the air by height and slope (io/terrain_colors.h).
enum class TerrainColors { none, land };

// Procedural height-field terrain (kim-lee-kobbelt §3 flight-simulator scene) with about
// `target_faces` triangles; same seed, same mesh, bit for bit. The colours never change a position.
Mesh make_terrain(uint64_t target_faces, uint32_t seed = 1, TerrainColors colors = TerrainColors::none);

}  // namespace pms
