// What to refine locally (gueziec et al. 1999, Fig. 15: "various criteria to decide which vertices of the
// surface should be locally split"): the vertex splits wanted for a region of space or for a view; the
// refinement (multilevel/local.h) adds what they need.
#pragma once
#include <cstdint>
#include <vector>

#include "common/camera.h"
#include "multilevel/dag.h"
#include "multilevel/mesh.h"

namespace pms {

// An axis-aligned box [lo, hi] or, when `sphere`, the ball around `lo` of radius `radius`.
struct Region {
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool sphere = false;
  float radius = 0;

  bool contains(const float p[3]) const;
};

// The collapses whose vertex lies in `region` and is of level >= `level`: refined down to LOD `level` there.
std::vector<uint32_t> splits_in_region(const MultilevelMesh& mesh, const MultilevelDag& dag, const Region& region,
                                       uint32_t level = 0);

// The screen-size rule: the collapses whose star (the ball of the node's radius around its vertex) meets
// the view frustum, does not face away from the eye (Hoppe 1997 §4.2's normal cone, MultilevelDag::cone)
// and would cover more than `pixels` pixels on screen (§4.3's kappa); in front of the near plane counts
// as large.
std::vector<uint32_t> splits_for_view(const MultilevelMesh& mesh, const MultilevelDag& dag, const ViewParams& view,
                                      float pixels);

}  // namespace pms
