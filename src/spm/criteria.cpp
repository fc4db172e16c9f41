// Hoppe 1997, "View-dependent refinement of progressive meshes", §4.1 (view frustum), §4.2 (surface
// orientation, normal cones), §4.3 (screen-space geometric error, deviation space D(mu, delta)).
// kim-lee-kobbelt 2005 §5.3: qrefine() is false for a real leaf, whatever the view.
#include "spm/criteria.h"
#include "spm/criteria_inline.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "common/error.h"
#include "common/portable_math.h"
#include "spm/refine_info.h"

namespace pms {
using namespace criteria_detail;

ViewCriteria make_criteria(const ViewParams& view, float tolerance_px) {
  if (!(tolerance_px >= 0) || !std::isfinite(tolerance_px)) fail("view", "tolerance must be a finite number >= 0");
  ViewCriteria c;
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 4; ++k) c.planes[i][k] = view.planes[i][k];
  for (int k = 0; k < 3; ++k) c.eye[k] = view.eye[k];
  const float kappa = tolerance_px * view.pixel_angle;
  c.kappa2 = kappa * kappa;
  return c;
}

NodeCriteria node_criteria(const float position[3], const RefineBounds& bounds) {
  NodeCriteria n = node_criteria_without_cone(position, bounds);
  // A cone of half-angle >= pi/2 holds opposite normals: some face below may always face the eye.
  if (bounds.cone_angle < std::numbers::pi_v<float> / 2) {
    // Portable: the sender-driven server and its client must agree on every back-face test.
    n.cos_a = portable_cos(bounds.cone_angle);
    n.sin_a = portable_sin(bounds.cone_angle);
  }
  return n;
}

namespace criteria_detail {

std::vector<ConeTrig> cone_trig_table() {
  std::vector<ConeTrig> trig(kConeSteps + 1);
  const float origin[3] = {0, 0, 0};
  RefineInfo info{};
  for (uint32_t u = 0; u <= kConeSteps; ++u) {
    info.cone_angle = uint16_t(u);
    const NodeCriteria n = node_criteria(origin, dequantize_refine(info, 1));
    trig[u] = {n.cos_a, n.sin_a};
  }
  return trig;
}

}  // namespace criteria_detail

bool outside_frustum(const ViewCriteria& view, const NodeCriteria& node) { return outside_frustum_inline(view, node); }
bool back_facing(const ViewCriteria& view, const NodeCriteria& node) { return back_facing_inline(view, node); }
bool screen_error_exceeds(const ViewCriteria& view, const NodeCriteria& node) {
  return screen_error_exceeds_inline(view, node);
}
bool qrefine(const ViewCriteria& view, const NodeCriteria& node) { return qrefine_inline(view, node); }

float refinement_priority(const ViewCriteria& view, const NodeCriteria& node) { return priority_inline(view, node); }

}  // namespace pms
