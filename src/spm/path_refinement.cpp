#include "spm/path_refinement.h"

#include <chrono>

#include "spm/adapt.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"

namespace pms {

VertexHierarchy complete_hierarchy(const ModelData& model) {
  VertexHierarchy h = VertexHierarchy::from_model(model);
  h.reserve(model.node_count());
  for (uint32_t node : model.split_order) h.add_split(split_record(model, node));
  return h;
}

PathRefinement refine_along(const ModelData& model, std::span<const Camera> path, float tolerance_px) {
  PathRefinement run;
  if (path.empty()) return run;
  VertexHierarchy h = complete_hierarchy(model);
  SelectiveMesh mesh(h, model.base_faces);
  SelectiveRefinement refinement(mesh, model.scale, AdaptOptions{tolerance_px, 0, 0});
  // The first view from the base mesh is a load, not a frame.
  refinement.set_view(make_view(path[0], model.bbox_min, model.bbox_max));
  refinement.converge();
  const auto start = std::chrono::steady_clock::now();
  for (const Camera& camera : path) {
    refinement.set_view(make_view(camera, model.bbox_min, model.bbox_max));
    run.ops += refinement.adapt().ops();
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.faces = mesh.face_count();
  run.frames = uint32_t(path.size());
  return run;
}

}  // namespace pms
