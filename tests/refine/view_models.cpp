#include "view_models.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "builder/build.h"
#include "common/error.h"
#include "io/shapes.h"
#include "pm/hierarchy.h"
#include "pm/refine_info.h"
#include "pm/split_record.h"
#include "pm/vertex_id.h"
#include "refine/criteria.h"
#include "refine/selective_mesh.h"
#include "refine/vertex_hierarchy.h"
#include "test_support.h"

namespace pms::test {
namespace {

BuiltModel build(const std::string& name, Mesh mesh, int up_axis, const BuildOptions& options = {}) {
  BuiltModel m;
  m.name = name;
  clean_mesh(mesh);
  BuildResult built = build_progressive_mesh(mesh, options);
  m.input = std::move(mesh);
  m.h = std::move(built.hierarchy);
  m.up_axis = up_axis;
  return m;
}

template <class T>
std::array<T, 3> rotated_to_min(std::array<T, 3> f) {
  std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
  return f;
}

}  // namespace

const BuiltModel& built_sphere() {
  static const BuiltModel m = build("sphere", make_sphere(40, 40), 1);
  return m;
}

const BuiltModel& built_terrain() {
  static const BuiltModel m = build("terrain", make_terrain(20000), 2);
  return m;
}

const BuiltModel& built_studded_plane(Deviation deviation) {
  auto make = [](Deviation measure) {
    constexpr int kCells = 48, kStudEvery = 6;
    Mesh mesh = make_grid(kCells, kCells);
    for (int y = 0; y <= kCells; ++y)
      for (int x = 0; x <= kCells; ++x) {
        const bool stud = x % kStudEvery == kStudEvery / 2 && y % kStudEvery == kStudEvery / 2;
        mesh.positions[3 * size_t(y * (kCells + 1) + x) + 2] = stud ? 0.01f : 0.0f;
      }
    BuildOptions options;
    options.deviation = measure;
    return build("studded plane", std::move(mesh), 2, options);
  };
  static const BuiltModel bound = make(Deviation::bound), estimate = make(Deviation::estimate);
  return deviation == Deviation::bound ? bound : estimate;
}

const BuiltModel* built_bunny() {
  static const std::unique_ptr<BuiltModel> m = [] {
    const auto path = shared_model("bunny.ply.xz");
    return path.empty() ? nullptr : std::make_unique<BuiltModel>(build("bunny", load_mesh(path.string()), 1));
  }();
  return m.get();
}

Camera framing_camera(const BuiltModel& model, std::array<float, 3> direction, float distance, float fovy) {
  const ModelData v = model.model();
  float centre[3], radius2 = 0;
  for (int k = 0; k < 3; ++k) {
    centre[k] = 0.5f * (v.bbox_min[k] + v.bbox_max[k]);
    radius2 += 0.25f * (v.bbox_max[k] - v.bbox_min[k]) * (v.bbox_max[k] - v.bbox_min[k]);
  }
  const float length = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
  const float frame = std::sqrt(radius2) / std::sin(0.5f * fovy * std::numbers::pi_v<float> / 180);
  Camera c;
  for (int k = 0; k < 3; ++k) {
    c.target[k] = centre[k];
    c.eye[k] = centre[k] + direction[k] / length * frame * distance;
    c.up[k] = k == model.up_axis ? 1.0f : 0.0f;
  }
  c.fovy_deg = fovy;
  return c;
}

ViewParams view_for(const BuiltModel& model, const Camera& camera) {
  return make_view(camera, model.h.bbox_min, model.h.bbox_max);
}

std::vector<IdFace> id_faces(const SelectiveMesh& mesh) {
  const VertexHierarchy& h = mesh.hierarchy();
  std::vector<IdFace> faces;
  for (uint32_t f = 0; f < mesh.face_capacity(); ++f) {
    if (!mesh.face_alive(f)) continue;
    IdFace face;
    for (int k = 0; k < 3; ++k) {
      const VertexId id = h.id(mesh.face(f)[k]);
      face[k] = {id.tree, id.node};
    }
    faces.push_back(rotated_to_min(face));
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

std::vector<std::array<uint32_t, 3>> leaf_input_faces(const SelectiveMesh& mesh, const BuiltModel& model) {
  const VertexHierarchy& h = mesh.hierarchy();
  const ModelData view = model.model();
  std::vector<std::array<uint32_t, 3>> faces;
  for (uint32_t f = 0; f < mesh.face_capacity(); ++f) {
    if (!mesh.face_alive(f)) continue;
    std::array<uint32_t, 3> face;
    bool leaves = true;
    for (int k = 0; k < 3 && leaves; ++k) {
      const uint32_t node = view.find(h.id(mesh.face(f)[k]));
      leaves = node != kNone && view.is_leaf(node);
      if (leaves) face[k] = view.leaf_vertex[node];
    }
    if (leaves) faces.push_back(rotated_to_min(face));
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

std::vector<std::array<uint32_t, 3>> canonical_input_faces(const Mesh& mesh) {
  std::vector<std::array<uint32_t, 3>> faces;
  for (size_t i = 0; i < mesh.indices.size(); i += 3)
    faces.push_back(rotated_to_min(std::array<uint32_t, 3>{mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]}));
  std::sort(faces.begin(), faces.end());
  return faces;
}

VertexHierarchy complete_hierarchy(const ModelData& view) {
  VertexHierarchy h = VertexHierarchy::from_model(view);
  h.reserve(view.node_count());
  for (uint32_t node = 0; node < view.node_count(); ++node)
    if (!view.is_leaf(node)) h.add_split(split_record(view, node));
  return h;
}

std::vector<IdFace> naive_refinement(const BuiltModel& model, const ViewParams& view, float tolerance) {
  const ModelData m = model.model();
  const VertexHierarchy h = complete_hierarchy(m);
  SelectiveMesh mesh(h, m.base_faces);
  const ViewCriteria criteria = make_criteria(view, tolerance);
  std::vector<uint32_t> active;
  for (bool progress = true; progress;) {
    progress = false;
    active.clear();  // a copy: splits reorder the active list
    for (uint32_t v : mesh.active_vertices()) active.push_back(v);
    for (uint32_t v : active) {
      if (!mesh.is_active(v) || h.is_leaf(v)) continue;
      if (!qrefine(criteria, h.position(v), dequantize_refine(h.refine(v), m.scale))) continue;
      if (!mesh.vsplit(v).done) throw Error("naive refinement: a complete hierarchy cannot block");
      progress = true;
    }
  }
  return id_faces(mesh);
}

RefinedFromAbove::RefinedFromAbove(const BuiltModel& model)
    : hierarchy(complete_hierarchy(model.model())), mesh(hierarchy, model.model().base_faces) {
  const ViewParams view = view_for(model, framing_camera(model, {0.05f, 0.02f, 1}, 1.2f, 5));
  SelectiveRefinement refinement(mesh, model.model().scale, AdaptOptions{0, 0, 0});
  refinement.set_view(view);
  refinement.converge();
}

}  // namespace pms::test
