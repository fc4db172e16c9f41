// SelVSplit / SelECol over partial hierarchies (kim-lee-kobbelt §4–5; Kim & Lee 2001), checked against
// the dual view: whatever the order of splits and collapses, the mesh equals the input faces mapped to
// their active ancestors (properties 1–3, docs/architecture.md), and the connectivity stays an oriented manifold.
#include <gtest/gtest.h>
#include <algorithm>
#include <random>
#include <string>

#include "common/error.h"
#include "error_of.h"
#include "reference_pm.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms {
namespace {

using test::Faces;
using test::ReferenceModel;

struct Case {
  std::string name;
  ReferenceModel model;
};

// Closed and open, genus 0 and 1, one and two boundary loops, long fans (the bipyramid's apexes outgrow
// a vertex's inline face list); built once, the collapser is slow.
const std::vector<Case>& cases() {
  static const std::vector<Case> all = [] {
    std::vector<Case> c;
    c.push_back({"octahedron", test::build_reference_model(test::make_octahedron(), 1)});
    c.push_back({"icosphere-a", test::build_reference_model(test::make_icosphere(2), 1)});
    c.push_back({"icosphere-b", test::build_reference_model(test::make_icosphere(2), 2)});
    c.push_back({"icosphere-c", test::build_reference_model(test::make_icosphere(3), 7)});
    c.push_back({"grid", test::build_reference_model(test::make_open_grid(10, 8), 3)});
    c.push_back({"torus", test::build_reference_model(test::make_torus_mesh(12, 8), 4)});
    c.push_back({"cylinder", test::build_reference_model(test::make_open_cylinder(6, 10), 5)});
    c.push_back({"bipyramid", test::build_reference_model(test::make_bipyramid(40), 6)});
    return c;
  }();
  return all;
}

VertexHierarchy complete_hierarchy(const ModelData& view) {
  VertexHierarchy h = VertexHierarchy::from_model(view);
  for (uint32_t node = 0; node < view.node_count(); ++node)  // breadth-first: parents first
    if (!view.is_leaf(node)) h.add_split(split_record(view, node));
  return h;
}

std::string invariants(const SelectiveMesh& mesh) {
  std::string why;
  return mesh.check_invariants(&why) ? "ok" : why;
}

// ActiveAncestor exactly as kim-lee-kobbelt §4 states it: shift the node-id right until it is active.
uint32_t right_shift_ancestor(const SelectiveMesh& mesh, VertexId v) {
  for (; v.node != 0; v.node >>= 1) {
    const uint32_t slot = mesh.hierarchy().find(v);
    if (slot != kNone && mesh.is_active(slot)) return slot;
  }
  return kNone;
}

// A copy: splits and collapses reorder the active list while we walk it.
std::vector<uint32_t> active_snapshot(const SelectiveMesh& mesh) {
  std::vector<uint32_t> active;
  for (uint32_t v : mesh.active_vertices()) active.push_back(v);
  return active;
}

void expect_dual_view(const SelectiveMesh& mesh, const ReferenceModel& model, const std::string& where) {
  ASSERT_EQ(test::mesh_faces(mesh), test::dual_view_faces(mesh, model)) << where;
}

TEST(SelectiveMesh, ReferenceModelsAreNontrivial) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const Hierarchy& h = c.model.h;
    EXPECT_GT(h.split_order.size(), 0u) << c.name;
    EXPECT_EQ(h.node_count(), 2 * size_t(c.model.input.vertex_count()) - h.root_count) << c.name;
    bool one_sided = false;
    for (uint32_t n : h.split_order) one_sided |= h.cut_left[n] == kNone || h.cut_right[n] == kNone;
    const bool open = c.name == "grid" || c.name == "cylinder";
    EXPECT_EQ(one_sided, open) << c.name << ": boundary splits exist exactly on open meshes";
    EXPECT_LE(h.root_count, 12u) << c.name;
    int depth = 0;
    for (size_t n = 0; n < h.node_count(); ++n) depth = std::max(depth, c.model.model().id(uint32_t(n)).depth());
    EXPECT_GE(depth, c.name == "octahedron" ? 1 : 4) << c.name;  // the octahedron only folds into a tetrahedron
    // The input itself is an oriented manifold: as a base mesh of its own vertices it passes the audit.
    VertexHierarchy flat;
    const float origin[3] = {0, 0, 0};
    for (uint32_t v = 0; v < c.model.input.vertex_count(); ++v) flat.add_root({v, 1}, origin, RefineInfo{});
    EXPECT_EQ(invariants(SelectiveMesh(flat, c.model.input.indices)), "ok") << c.name;
  }
}

TEST(SelectiveMesh, PmOrderReproducesTheInput) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const ModelData view = c.model.model();
    VertexHierarchy h = VertexHierarchy::from_model(view);
    SelectiveMesh mesh(h, view.base_faces);
    ASSERT_EQ(invariants(mesh), "ok") << c.name;
    ASSERT_EQ(test::mesh_faces(mesh), test::base_faces(c.model, h)) << c.name;
    for (uint32_t node : view.split_order) {
      // Packets arrive in PM order, each applied at once: never needs the partial-order recursion.
      h.add_split(split_record(view, node));
      const size_t before = mesh.vertex_count();
      const VSplitResult r = mesh.vsplit(h.find(view.id(node)));
      ASSERT_TRUE(r.done) << c.name;
      ASSERT_EQ(mesh.vertex_count(), before + 1) << c.name;
      ASSERT_EQ(invariants(mesh), "ok") << c.name << " after node " << node;
      expect_dual_view(mesh, c.model, c.name);
    }
    EXPECT_EQ(mesh.vertex_count(), c.model.input.vertex_count()) << c.name;
    EXPECT_EQ(test::leaf_faces(mesh, c.model), test::canonical_input(c.model.input)) << c.name;
  }
}

TEST(SelectiveMesh, BreadthFirstOrderReproducesTheInput) {
  size_t forced = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const ModelData view = c.model.model();
    const VertexHierarchy h = complete_hierarchy(view);
    SelectiveMesh mesh(h, view.base_faces);
    for (uint32_t node = 0; node < view.node_count(); ++node) {
      const uint32_t slot = h.find(view.id(node));
      if (view.is_leaf(node) || !mesh.is_active(slot)) continue;  // inactive: split earlier by the partial order
      const size_t before = mesh.vertex_count();
      ASSERT_TRUE(mesh.vsplit(slot).done) << c.name;
      forced += mesh.vertex_count() - before - 1;
      ASSERT_EQ(invariants(mesh), "ok") << c.name;
    }
    expect_dual_view(mesh, c.model, c.name);
    EXPECT_EQ(test::leaf_faces(mesh, c.model), test::canonical_input(c.model.input)) << c.name;
  }
  EXPECT_GT(forced, 0u) << "no split needed v_l == v_r split first: the partial order went untested";
}

// Packets arrive in a random order (any parent before its children, as a server sends them); the client
// splits whatever it can and keeps the rest pending until their blockers arrive (property 3).
TEST(SelectiveMesh, RandomArrivalOrderReproducesTheInput) {
  size_t blocked = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    for (uint32_t seed = 1; seed <= 4; ++seed) {
      std::mt19937 rng(seed);
      const ModelData view = c.model.model();
      VertexHierarchy h = VertexHierarchy::from_model(view);
      SelectiveMesh mesh(h, view.base_faces);
      std::vector<uint32_t> available;  // internal nodes whose parent is known
      for (uint32_t r = 0; r < view.root_count; ++r)
        if (!view.is_leaf(r)) available.push_back(r);
      while (!available.empty()) {
        const size_t pick = std::uniform_int_distribution<size_t>(0, available.size() - 1)(rng);
        const uint32_t node = available[pick];
        available[pick] = available.back();
        available.pop_back();
        h.add_split(split_record(view, node));
        for (uint32_t child : {view.first_child[node], view.first_child[node] + 1})
          if (!view.is_leaf(child)) available.push_back(child);
        // Split every active vertex whose packet is known, until nothing more can be done.
        for (bool progress = true; progress;) {
          progress = false;
          const std::vector<uint32_t> active = active_snapshot(mesh);
          for (uint32_t v : active) {
            if (!mesh.is_active(v) || h.is_leaf(v)) continue;
            const VSplitResult r = mesh.vsplit(v);
            if (r.done) {
              progress = true;
              continue;
            }
            ++blocked;
            ASSERT_TRUE(mesh.is_active(r.needs) && h.is_leaf(r.needs)) << c.name;
          }
        }
        ASSERT_EQ(invariants(mesh), "ok") << c.name;
      }
      expect_dual_view(mesh, c.model, c.name);
      EXPECT_EQ(test::leaf_faces(mesh, c.model), test::canonical_input(c.model.input)) << c.name << " seed " << seed;
    }
  }
  EXPECT_GT(blocked, 0u) << "no split ever waited for an unknown packet: that path went untested";
}

// Random legal vsplits and ecols (property 2), then collapse everything back to the base mesh.
TEST(SelectiveMesh, RandomInterleavingsStayManifoldAndCollapseToTheBase) {
  constexpr int kOps = 2000;
  size_t splits = 0, collapses = 0, refused = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const ModelData view = c.model.model();
    const VertexHierarchy h = complete_hierarchy(view);
    // A sanitizer build walks one seed of the three: the same checks, a third of the time under ASan.
    for (uint32_t seed = 1; seed <= (test::kSanitized ? 1u : 3u); ++seed) {
      std::mt19937 rng(seed * 7919 + uint32_t(c.name.size()));
      SelectiveMesh mesh(h, view.base_faces);
      size_t finest = 0;
      for (int op = 0; op < kOps; ++op) {
        finest = std::max(finest, mesh.vertex_count());
        const auto active = mesh.active_vertices();
        auto pick = [&] { return active[std::uniform_int_distribution<size_t>(0, active.size() - 1)(rng)]; };
        const std::string where = c.name + " seed " + std::to_string(seed) + " op " + std::to_string(op);
        // Refining first, so the fronts reach the leaves, then coarsening; both kinds throughout.
        const bool split = std::uniform_int_distribution<int>(0, 99)(rng) < (op < kOps / 2 ? 70 : 30);
        uint32_t v = pick();
        for (int tries = 0; split && h.is_leaf(v) && tries < 16; ++tries) v = pick();
        if (split && !h.is_leaf(v)) {
          ASSERT_TRUE(mesh.vsplit(v).done) << where;
          ++splits;
        } else if (!split && h.parent(v) != kNone) {
          const uint32_t p = h.parent(v);
          const bool siblings_active = mesh.is_active(h.first_child(p)) && mesh.is_active(h.first_child(p) + 1);
          const Faces before = op % 10 == 0 ? test::mesh_faces(mesh) : Faces{};
          if (mesh.ecol(p)) {
            ++collapses;
          } else {
            refused += siblings_active;
            if (op % 10 == 0) {
              ASSERT_EQ(test::mesh_faces(mesh), before) << where << ": refused ecol changed the mesh";
            }
          }
        }
        ASSERT_EQ(invariants(mesh), "ok") << where;
        if (op % 25 == 0) {
          expect_dual_view(mesh, c.model, where);
          for (uint32_t leaf = 0; leaf < c.model.input.vertex_count(); ++leaf) {
            const VertexId id = view.id(c.model.leaf_node[leaf]);
            ASSERT_EQ(mesh.active_ancestor(id), right_shift_ancestor(mesh, id)) << where;
          }
        }
      }
      // The walk went most of the way to the input and back.
      EXPECT_GT(finest, c.model.input.vertex_count() * 3 / 4) << c.name << " seed " << seed;
      // Collapse until nothing is left to collapse: every front can return to the roots.
      for (bool progress = true; progress;) {
        progress = false;
        const std::vector<uint32_t> active = active_snapshot(mesh);
        for (uint32_t v : active)
          if (mesh.is_active(v) && h.parent(v) != kNone && mesh.ecol(h.parent(v))) progress = true;
        ASSERT_EQ(invariants(mesh), "ok") << c.name;
      }
      EXPECT_EQ(mesh.vertex_count(), view.root_count) << c.name << " seed " << seed;
      EXPECT_EQ(test::mesh_faces(mesh), test::base_faces(c.model, h)) << c.name << " seed " << seed;
    }
  }
  EXPECT_GT(splits, 1000u);
  EXPECT_GT(collapses, 1000u);
  // Collapses refused with both children active: the reverse partial order at work.
  EXPECT_GT(refused, 0u);
  std::printf("random interleavings: %zu vsplits, %zu ecols, %zu refused\n", splits, collapses, refused);
}

TEST(SelectiveMesh, ExtractGivesTheCurrentMesh) {
  const ReferenceModel& model = cases()[1].model;
  const ModelData view = model.model();
  const VertexHierarchy h = complete_hierarchy(view);
  SelectiveMesh mesh(h, view.base_faces);
  for (uint32_t node : view.split_order) ASSERT_TRUE(mesh.vsplit(h.find(view.id(node))).done);
  MeshArrays out;
  mesh.extract(out);
  ASSERT_EQ(out.slots.size(), model.input.vertex_count());
  ASSERT_EQ(out.positions.size(), 3 * out.slots.size());
  ASSERT_EQ(out.normals.size(), 3 * out.slots.size());
  ASSERT_EQ(out.colors.size(), 4 * out.slots.size());
  ASSERT_EQ(out.indices.size(), model.input.indices.size());
  std::vector<uint32_t> leaf(out.slots.size());
  for (size_t i = 0; i < out.slots.size(); ++i) {
    leaf[i] = model.h.leaf_vertex[model.node_of(h.id(out.slots[i]))];
    for (int k = 0; k < 3; ++k) EXPECT_EQ(out.positions[3 * i + k], model.input.positions[3 * leaf[i] + k]);
    EXPECT_EQ(out.normals[3 * i], model.h.normals[3 * model.leaf_node[leaf[i]]]);
    EXPECT_EQ(out.colors[4 * i + 3], model.h.colors[4 * model.leaf_node[leaf[i]] + 3]);
  }
  Faces faces;
  for (size_t i = 0; i < out.indices.size(); i += 3)
    faces.push_back({leaf[out.indices[i]], leaf[out.indices[i + 1]], leaf[out.indices[i + 2]]});
  EXPECT_EQ(test::canonical(faces), test::canonical_input(model.input));
}

// Prefetching is a hint for any slot a caller may name: known or not, active or not, split or not, even
// past the end of what the mesh has seen of a growing hierarchy. It reads nothing out of bounds (the
// sanitizer build checks) and changes nothing.
TEST(SelectiveMesh, PrefetchAnySlotChangesNothing) {
  const ReferenceModel& model = cases()[1].model;
  const ModelData view = model.model();
  const VertexHierarchy h = complete_hierarchy(view);
  SelectiveMesh mesh(h, view.base_faces);
  const size_t half = view.split_order.size() / 2;
  for (size_t i = 0; i < half; ++i) ASSERT_TRUE(mesh.vsplit(h.find(view.id(view.split_order[i]))).done);
  const Faces before = test::mesh_faces(mesh);
  for (uint32_t slot = 0; slot < h.size() + 4; ++slot)
    for (int stage = 0; stage < SelectiveMesh::kPrefetchStages; ++stage) {
      mesh.prefetch_vsplit(slot, stage);
      mesh.prefetch_ecol(slot, stage);
    }
  EXPECT_EQ(test::mesh_faces(mesh), before);
  EXPECT_EQ(invariants(mesh), "ok");
  // The rest in PM order with every stage prefetched ahead, as the bench does: the same finest mesh;
  // then every collapse in reverse, prefetched the same way: the base mesh.
  const auto slot_at = [&](size_t i) { return h.find(view.id(view.split_order[i])); };
  const auto& ahead = SelectiveMesh::kPrefetchAhead;
  const size_t n = view.split_order.size();
  for (size_t i = half; i < n; ++i) {
    for (int stage = 0; stage < SelectiveMesh::kPrefetchStages; ++stage)
      if (i + ahead[stage] < n) mesh.prefetch_vsplit(slot_at(i + ahead[stage]), stage);
    ASSERT_TRUE(mesh.vsplit(slot_at(i)).done);
  }
  EXPECT_EQ(test::leaf_faces(mesh, model), test::canonical_input(model.input));
  for (size_t i = n; i-- > 0;) {
    for (int stage = 0; stage < SelectiveMesh::kPrefetchStages; ++stage)
      if (i >= ahead[stage]) mesh.prefetch_ecol(slot_at(i - ahead[stage]), stage);
    ASSERT_TRUE(mesh.ecol(slot_at(i)));
  }
  EXPECT_EQ(mesh.face_count(), view.base_faces.size() / 3);
}

TEST(SelectiveMesh, RejectsBadBaseMeshes) {
  VertexHierarchy h;
  const float p[3] = {0, 0, 0};
  for (uint32_t r = 0; r < 5; ++r) h.add_root({r, 1}, p, RefineInfo{});
  auto build = [&](std::vector<uint32_t> faces) { SelectiveMesh mesh(h, faces); };
  EXPECT_THROW(build({0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 1, 4}), Error);  // edge 0->1 twice
  EXPECT_THROW(build({0, 1, 2, 2, 3, 9, 0, 3, 4}), Error);           // unknown root
  EXPECT_THROW(build({0, 1, 1, 0, 2, 3, 0, 3, 4}), Error);           // degenerate face
  EXPECT_THROW(build({0, 1, 2, 0, 2, 3}), Error);                    // root 4 unused
  EXPECT_THROW(build({0, 1, 2, 0, 3, 4}), Error);                    // two fans meet at root 0
  EXPECT_THROW(build({0, 1, 2, 0}), Error);                          // not whole triangles
  SelectiveMesh fan(h, std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4});
  EXPECT_EQ(invariants(fan), "ok");
  EXPECT_EQ(fan.vertex_count(), 5u);
  EXPECT_EQ(fan.face_count(), 3u);
}

// A repeated directed edge is found at a short fan (compared pairwise) and at a long one (sorted), and
// named by its root.
TEST(SelectiveMesh, RejectsARepeatedDirectedEdgeAtAnyFanLength) {
  for (const uint32_t spokes : {4u, 40u}) {
    VertexHierarchy h;
    const float p[3] = {0, 0, 0};
    for (uint32_t r = 0; r <= spokes + 1; ++r) h.add_root({r, 1}, p, RefineInfo{});
    std::vector<uint32_t> faces;
    for (uint32_t i = 1; i <= spokes; ++i) faces.insert(faces.end(), {0, i, i + 1});
    SelectiveMesh open_fan(h, faces);
    EXPECT_EQ(open_fan.face_count(), spokes) << spokes;
    faces.insert(faces.end(), {0, spokes / 2, spokes + 1});  // 0 -> spokes/2 again
    const std::string message = test::error_of([&] { SelectiveMesh mesh(h, faces); });
    EXPECT_NE(message.find("root <0,1>: edge used twice in the same direction"), std::string::npos)
        << spokes << ": " << message;
  }
}

// Packets that contradict the mesh are reported, and the mesh is left as it was.
TEST(SelectiveMesh, RejectsInconsistentSplits) {
  const ReferenceModel model = test::build_reference_model(test::make_icosphere(1), 3, 20);
  const ModelData view = model.model();
  VertexHierarchy h = VertexHierarchy::from_model(view);
  SelectiveMesh mesh(h, view.base_faces);
  ASSERT_GE(h.root_count(), 20u);
  // Two roots that are not neighbours of root 0.
  std::vector<uint8_t> neighbour(h.root_count(), 0);
  for (size_t i = 0; i < view.base_faces.size(); i += 3)
    for (int k = 0; k < 3; ++k)
      if (view.base_faces[i + k] == 0)
        neighbour[view.base_faces[i + (k + 1) % 3]] = neighbour[view.base_faces[i + (k + 2) % 3]] = 1;
  std::vector<uint32_t> far;
  uint32_t near = kNone;
  for (uint32_t r = 1; r < h.root_count(); ++r) {
    if (!neighbour[r]) far.push_back(r);
    else if (near == kNone) near = r;
  }
  ASSERT_GE(far.size(), 2u);
  ASSERT_NE(near, kNone);

  SplitRecord bogus;
  bogus.vs = {0, 1};
  bogus.cut_l = {far[0], 1};
  bogus.cut_r = {far[1], 1};
  bogus.has_normal = bogus.has_color = true;
  h.add_split(bogus);
  const Faces before = test::mesh_faces(mesh);
  EXPECT_THROW(mesh.vsplit(h.find({0, 1})), Error);
  EXPECT_EQ(test::mesh_faces(mesh), before);
  EXPECT_EQ(invariants(mesh), "ok");

  // A one-sided split of an interior vertex of a closed mesh.
  bogus.vs = {near, 1};
  bogus.cut_l = {0, 1};
  bogus.cut_r = kNoVertex;
  h.add_split(bogus);
  EXPECT_THROW(mesh.vsplit(h.find({near, 1})), Error);
  EXPECT_EQ(test::mesh_faces(mesh), before);
  EXPECT_EQ(invariants(mesh), "ok");

  // Collapsing them back is refused (the children are not active), and misuse is an error.
  EXPECT_FALSE(mesh.ecol(h.find({0, 1})));
  EXPECT_THROW(mesh.ecol(h.find({far[0], 1})), Error);  // no known children
  EXPECT_THROW(mesh.vsplit(h.find({0, 2})), Error);     // not active
  EXPECT_EQ(mesh.active_ancestor({0, 2}), h.find({0, 1}));
  EXPECT_EQ(mesh.active_ancestor({h.root_count(), 1}), kNone);
}

TEST(SelectiveMesh, SplitOfAnUnknownLeafIsReported) {
  const ReferenceModel& model = cases()[1].model;
  const ModelData view = model.model();
  const VertexHierarchy h = VertexHierarchy::from_model(view);
  SelectiveMesh mesh(h, view.base_faces);
  const VSplitResult r = mesh.vsplit(0);
  EXPECT_FALSE(r.done);
  EXPECT_EQ(r.needs, 0u);
  EXPECT_EQ(invariants(mesh), "ok");
}

}  // namespace
}  // namespace pms
