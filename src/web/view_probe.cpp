#include "web/view_probe.h"

#include <cmath>
#include <cstring>

#include "common/camera.h"
#include "common/error.h"
#include "spm/criteria.h"
#include "spm/refine_info.h"

namespace pms::web {

Camera camera_of(const float* c, uint32_t width, uint32_t height) {
  Camera camera;
  for (int k = 0; k < 3; ++k) {
    camera.eye[k] = c[k];
    camera.target[k] = c[3 + k];
    camera.up[k] = c[6 + k];
  }
  camera.fovy_deg = c[9];
  camera.width = width;
  camera.height = height;
  return camera;
}

void probe_view_math(const float* in, float* out) {
  const Camera camera = camera_of(in, uint32_t(in[10]), uint32_t(in[11]));
  const float* box = in + 12;
  const float tolerance = in[18];
  const float* node = in + 19;

  RefineBounds bounds{};
  bounds.radius = node[3], bounds.mu = node[4], bounds.delta = node[5];
  for (int k = 0; k < 3; ++k) bounds.axis[k] = node[6 + k];
  bounds.cone_angle = node[9];
  const NodeCriteria n = node_criteria(node, bounds);
  out[59] = n.cos_a;
  out[60] = n.sin_a;
  try {
    const ViewParams v = make_view(camera, box, box + 3);
    std::memcpy(out, v.view.m, 16 * sizeof(float));
    std::memcpy(out + 16, v.projection.m, 16 * sizeof(float));
    std::memcpy(out + 32, v.planes, 24 * sizeof(float));
    out[56] = v.near_plane, out[57] = v.far_plane, out[58] = v.pixel_angle;
    const ViewCriteria c = make_criteria(v, tolerance);
    out[61] = float(int(outside_frustum(c, n)) | int(back_facing(c, n)) << 1 | int(screen_error_exceeds(c, n)) << 2 |
                    int(qrefine(c, n)) << 3);
  } catch (const Error&) {
    for (size_t i = 0; i < 59; ++i) out[i] = NAN;
    out[61] = -1;
  }
}

}  // namespace pms::web
