// Wanted vertex splits for a region or a view (gueziec et al. 1999, Fig. 15); the screen-size rule is the
// one the progressive meshes' view criteria use (Hoppe 1997 §4.3).
#include "multilevel/region.h"

namespace pms {
namespace {

// A 2D file's vertices lie in z = 0.
void position_of(const MultilevelMesh& m, uint32_t v, float p[3]) {
  p[2] = 0;
  for (uint32_t k = 0; k < m.dimension; ++k) p[k] = m.positions[size_t(v) * m.dimension + k];
}

bool ball_meets_frustum(const ViewParams& view, const float p[3], float radius) {
  for (const auto& plane : view.planes)
    if (plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3] < -radius) return false;
  return true;
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
    position_of(m, v, p);
    if (region.contains(p)) out.push_back(v);
  }
  return out;
}

std::vector<uint32_t> splits_for_view(const MultilevelMesh& m, const MultilevelDag& dag, const ViewParams& view,
                                      float pixels) {
  std::vector<uint32_t> out;
  for (uint32_t v = dag.top_vertices; v < dag.vertices; ++v) {
    float p[3];
    position_of(m, v, p);
    const float radius = dag.radius[v - dag.top_vertices];
    if (!ball_meets_frustum(view, p, radius)) continue;
    const float depth = (p[0] - view.eye[0]) * view.forward[0] + (p[1] - view.eye[1]) * view.forward[1] +
                        (p[2] - view.eye[2]) * view.forward[2];
    if (depth <= view.near_plane || radius > pixels * depth * view.pixel_angle) out.push_back(v);
  }
  return out;
}

}  // namespace pms
