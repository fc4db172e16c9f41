// The view math the protocol needs both ends to agree on (make_view, the node tests of criteria.h), as
// flat floats in and out, so the WASM module and a native program evaluate the same cases and a test
// compares their outputs bit for bit (tests/web/wasm_view_math.mjs). Compiled by both builds.
#pragma once
#include <cstddef>
#include <cstdint>

#include "common/camera.h"

namespace pms::web {

// A camera as the page hands it over: eye, target, up (9 floats), fovy in degrees; and its viewport.
Camera camera_of(const float* c, uint32_t width, uint32_t height);

// One case in: camera eye, target, up (9), fovy in degrees, width, height, the model's box min and max (6),
// τ in pixels, a node's position (3), radius, mu, delta, cone axis (3) and cone angle.
constexpr size_t kProbeInputs = 30;
// One case out: the view matrix (16), projection (16), the 6 frustum planes (24), near, far, pixel angle
// (all NaN for a camera make_view refuses), the cone's cos and sin, then the node's four tests as bits
// (outside_frustum, back_facing, screen_error_exceeds, qrefine; -1 for a refused camera).
constexpr size_t kProbeOutputs = 62;

void probe_view_math(const float* in, float* out);

}  // namespace pms::web
