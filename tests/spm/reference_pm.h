// Test-only: small meshes and a slow reference half-edge collapser that produces complete hierarchies
// (roots, splits, fundamental cut leaves by the dual-view rule of docs/internals.md), so the refinement engine
// can be tested without the builder. Integration tests against build_progressive_mesh live elsewhere.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::test {

struct TestMesh {
  std::vector<float> positions;   // 3 per vertex
  std::vector<uint32_t> indices;  // 3 per face, CCW
  uint32_t vertex_count() const { return uint32_t(positions.size() / 3); }
};

TestMesh make_octahedron();
TestMesh make_icosphere(int subdivisions);             // closed, genus 0
TestMesh make_open_grid(int nx, int ny);               // one boundary loop
TestMesh make_torus_mesh(int rings, int segments);     // closed, genus 1
TestMesh make_open_cylinder(int rings, int segments);  // two boundary loops
TestMesh make_bipyramid(int ring);                     // closed; the two apexes have `ring` faces each

// A complete progressive mesh of `input` made of random valid half-edge collapses (each checked by
// simulating it and auditing the result), packed breadth-first like the builder's output.
struct ReferenceModel {
  TestMesh input;
  Hierarchy h;                      // ids filled; normals and colors derived from the leaves
  std::vector<uint32_t> leaf_node;  // input vertex -> packed node
  std::map<std::pair<uint32_t, uint64_t>, uint32_t> node_by_id;

  ModelData model() const;
  uint32_t node_of(VertexId id) const;  // packed node, kNone if unknown
};

ReferenceModel build_reference_model(const TestMesh& mesh, uint32_t seed, uint32_t min_vertices = 4);

using Faces = std::vector<std::array<uint32_t, 3>>;

// Each face rotated to start at its smallest index, then sorted: equal iff same faces, same orientation.
Faces canonical(Faces faces);
Faces canonical_input(const TestMesh& mesh);
// The mesh's faces in slots.
Faces mesh_faces(const SelectiveMesh& mesh);
// The dual view (Kim & Lee 2001): every input face with corners mapped to their active ancestors,
// faces that became degenerate dropped. A correct mesh equals this for its front.
Faces dual_view_faces(const SelectiveMesh& mesh, const ReferenceModel& model);
// The mesh's faces as input vertex indices (every active vertex must be a leaf).
Faces leaf_faces(const SelectiveMesh& mesh, const ReferenceModel& model);
// Base faces of the model in root slots of `hierarchy`.
Faces base_faces(const ReferenceModel& model, const VertexHierarchy& hierarchy);

}  // namespace pms::test
