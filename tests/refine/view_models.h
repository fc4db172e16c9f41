// Test-only: models built by the real builder (generated shapes, the terrain, the shared bunny), cameras
// that frame them, and meshes compared by vertex ids, for the view-dependent refinement tests.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "builder/build.h"
#include "io/mesh.h"
#include "pm/hierarchy.h"
#include "refine/adapt.h"
#include "refine/camera.h"
#include "refine/selective_mesh.h"
#include "refine/vertex_hierarchy.h"

namespace pms::test {

struct BuiltModel {
  std::string name;
  Mesh input;        // the cleaned input the hierarchy's leaves index
  Hierarchy h;
  int up_axis = 1;   // 1 = y (scans), 2 = z (terrain)
  ModelData model() const { return model_of(h); }
};

const BuiltModel& built_sphere();   // make_sphere, ~3k faces
const BuiltModel& built_terrain();  // make_terrain, ~20k faces, z up
const BuiltModel* built_bunny();    // ../shared/models/bunny.ply.xz, nullptr when absent
// A flat square (z = 0, z up) with a stud every few vertices: collapses in the flat part change
// nothing, while a flat vertex next to a stud lies on the coarse surface although its faces do not.
const BuiltModel& built_studded_plane(Deviation deviation = Deviation::estimate);

// Looks at the model's bounding-box centre from `direction` (need not be unit) at `distance` times the
// distance that just frames its bounding sphere; up is the model's up axis.
Camera framing_camera(const BuiltModel& model, std::array<float, 3> direction, float distance, float fovy = 45);
ViewParams view_for(const BuiltModel& model, const Camera& camera);

// A mesh as faces of vertex ids, each face rotated to start at its smallest id, sorted: equal iff the
// same front and the same faces with the same orientation.
using IdFace = std::array<std::pair<uint32_t, uint64_t>, 3>;
std::vector<IdFace> id_faces(const SelectiveMesh& mesh);
// The mesh's faces whose corners are all leaves, as sorted input-vertex triples (rotated to the smallest).
std::vector<std::array<uint32_t, 3>> leaf_input_faces(const SelectiveMesh& mesh, const BuiltModel& model);
std::vector<std::array<uint32_t, 3>> canonical_input_faces(const Mesh& mesh);

// Every internal node's vsplit packet, breadth-first.
VertexHierarchy complete_hierarchy(const ModelData& view);

// A model refined through the engine at τ = 0 px, seen from high above with a narrow lens (z up): every
// face is in view and faces the eye, so only the deviation bounds decide what stays coarse.
struct RefinedFromAbove {
  VertexHierarchy hierarchy;
  SelectiveMesh mesh;  // over `hierarchy`: the struct stays where it was made
  explicit RefinedFromAbove(const BuiltModel& model);
};

// The target mesh the simplest way: from the base, split every active vertex that qrefine wants, until
// nothing changes (no collapses, complete hierarchy). By construction the least fixed point.
std::vector<IdFace> naive_refinement(const BuiltModel& model, const ViewParams& view, float tolerance);

}  // namespace pms::test
