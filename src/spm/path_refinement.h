// The adaptation loop alone along a camera path, with every split of the model known (nothing to fetch):
// the refinement engine's throughput as one number, measured the same way by the native bench and inside
// the browser's WASM module (src/web/bench_api.cpp), so the two builds of the same code can be compared.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/camera.h"
#include "spm/hierarchy.h"
#include "spm/vertex_hierarchy.h"

namespace pms {

// Every split of `model` added in PM order: a hierarchy with nothing left to fetch.
VertexHierarchy complete_hierarchy(const ModelData& model);

struct PathRefinement {
  uint64_t ops = 0;    // vsplits and ecols performed along the path
  double seconds = 0;  // set_view + adapt over the whole path, one steady clock read at each end
  uint64_t faces = 0;  // the mesh's faces at the last camera
  uint32_t frames = 0;
  double ops_per_second() const { return seconds > 0 ? double(ops) / seconds : 0; }
};

// From the base mesh converged (untimed) at path[0], one adapt() per camera at τ = `tolerance_px`. The
// whole loop is timed at once: a browser's clock is coarse, and one read per frame would add its grain.
PathRefinement refine_along(const ModelData& model, std::span<const Camera> path, float tolerance_px);

}  // namespace pms
