// The view model every mode shares: a camera as CAM.json writes it (docs/cli.md) and the derived
// transforms the criteria (Hoppe 1997 §4) and the renderer evaluate. One derivation for both, so the
// refined mesh for a view and the image of that view agree on what "in view" means.
// Shared with the browser build: plain arithmetic, single-threaded.
#pragma once
#include <cstdint>
#include <optional>

namespace pms {

struct Camera {
  float eye[3] = {0, 0, 3};
  float target[3] = {0, 0, 0};
  float up[3] = {0, 1, 0};
  float fovy_deg = 45;   // vertical field of view
  uint32_t width = 800;  // viewport in pixels
  uint32_t height = 600;
};

// Row-major 4x4; clip = M * (x, y, z, 1), OpenGL conventions (right-handed eye space looking down -z,
// clip z in [-w, w]).
struct Mat4 {
  float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

struct ViewParams {
  Camera camera;
  float near_plane = 0.01f, far_plane = 100;
  Mat4 view;             // model -> eye
  Mat4 projection;       // eye -> clip
  Mat4 view_projection;  // model -> clip
  // The 6 frustum planes in model space, (a, b, c, d) with unit (a, b, c) pointing inside:
  // a point p is inside when a*p.x + b*p.y + c*p.z + d >= 0 for all six (left, right, bottom, top, near, far).
  float planes[6][4] = {};
  float eye[3] = {0, 0, 0};
  float forward[3] = {0, 0, -1};  // unit view direction
  // Screen-space error factor: a deviation of length e at eye distance z covers e / (z * pixel_angle)
  // pixels, pixel_angle = 2 tan(fovy / 2) / height (Hoppe 1997 §4.3, kappa).
  float pixel_angle = 0;
};

// Near/far planes enclose the box [box_min, box_max] seen from the camera (near clamped to far * 1e-4,
// so a camera inside the box still gets a usable depth range). Throws pms::Error for a degenerate
// camera (eye == target, up parallel to the view direction, fovy outside (0, 180), empty viewport).
ViewParams make_view(const Camera& camera, const float box_min[3], const float box_max[3]);
// What make_view would refuse `camera` for, or null when it makes a view (eye, target or up not finite,
// and an up within about a microradian of the view direction, count as degenerate too).
const char* camera_problem(const Camera& camera);

// The camera one frame on, if it moves as it did from `a` to `b` (the eye one step further, the view direction
// turned on as far again, at b's distance from its target; b's up, field of view and viewport), and `steps`
// frames on by repeating that step. Nothing when a direction is degenerate. The prefetch of the
// receiver-driven client and the idle time of the sender-driven one predict the path with it.
std::optional<Camera> extrapolate(const Camera& a, const Camera& b, uint32_t steps = 1);

Mat4 multiply(const Mat4& a, const Mat4& b);
// (x, y, z, 1) -> 4 clip coordinates.
void transform_point(const Mat4& m, const float p[3], float clip[4]);

}  // namespace pms
