// Wanted vertex splits for a region or a view (gueziec et al. 1999, Fig. 15); the screen-size rule is the
// one the progressive meshes' view criteria use (Hoppe 1997 §4.3).
#include "multilevel/region.h"

namespace pms {
namespace {

bool ball_meets_frustum(const ViewParams& view, const float p[3], float radius) {
  for (const auto& plane : view.planes)
    if (plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3] < -radius) return false;
  return true;
}

// Hoppe 1997 §4.2: the star faces away from the eye when every normal of its cone does, seen from its vertex.
bool back_facing(const ViewParams& view, const float p[3], const float cone[4]) {
  const float d[3] = {p[0] - view.eye[0], p[1] - view.eye[1], p[2] - view.eye[2]};
  const float along = cone[0] * d[0] + cone[1] * d[1] + cone[2] * d[2];
  return along > 0 && along * along > (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * cone[3];
}

}  // namespace

bool Region::contains(const float p[3]) const {
  if (sphere) {
    float d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (p[k] - lo[k]) * (p[k] - lo[k]);
    return d2 <= radius * radius;
  }
  for (int k = 0; k < 3; ++k)
    if (!(p[k] >= lo[k] && p[k] <= hi[k])) return false;
  return true;
}

std::vector<uint32_t> splits_in_region(const MultilevelMesh& m, const MultilevelDag& dag, const Region& region,
                                       uint32_t level) {
  std::vector<uint32_t> out;
  const uint32_t end = level < m.level_count() ? m.vertex_count[level] : dag.top_vertices;
  for (uint32_t v = dag.top_vertices; v < end; ++v) {
    float p[3];
    m.point(v, p);
    if (region.contains(p)) out.push_back(v);
  }
  return out;
}

std::vector<uint32_t> splits_for_view(const MultilevelMesh& m, const MultilevelDag& dag, const ViewParams& view,
                                      float pixels) {
  std::vector<uint32_t> out;
  for (uint32_t v = dag.top_vertices; v < dag.vertices; ++v) {
    float p[3];
    m.point(v, p);
    const float radius = dag.radius[v - dag.top_vertices];
    if (!ball_meets_frustum(view, p, radius)) continue;
    if (back_facing(view, p, &dag.cone[4 * size_t(v - dag.top_vertices)])) continue;
    const float depth = (p[0] - view.eye[0]) * view.forward[0] + (p[1] - view.eye[1]) * view.forward[1] +
                        (p[2] - view.eye[2]) * view.forward[2];
    if (depth <= view.near_plane || radius > pixels * depth * view.pixel_angle) out.push_back(v);
  }
  return out;
}

}  // namespace pms
