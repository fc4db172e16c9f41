// qrefine (Hoppe 1997 §4): frustum, normal cone and screen-space error, each checked against a direct
// computation; the cone test is checked to be conservative by sampling the sphere and the cone.
#include <gtest/gtest.h>
#include <cmath>
#include <numbers>
#include <random>

#include "builder/build.h"
#include "common/error.h"
#include "io/shapes.h"
#include "spm/criteria.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"

namespace pms {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Eye at (0, 0, 5) looking down -z at the unit box.
ViewParams test_view(float fovy = 45, uint32_t width = 800, uint32_t height = 600) {
  Camera camera;
  camera.eye[2] = 5;
  camera.fovy_deg = fovy;
  camera.width = width;
  camera.height = height;
  const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  return make_view(camera, lo, hi);
}

NodeCriteria node_at(float x, float y, float z, float radius, float mu = 0, float delta = 0) {
  RefineBounds b;
  b.radius = radius;
  b.mu = mu;
  b.delta = delta;
  b.cone_angle = kPi;  // no cone
  const float p[3] = {x, y, z};
  return node_criteria(p, b);
}

NodeCriteria with_cone(NodeCriteria n, const float axis[3], float angle) {
  RefineBounds b;
  b.radius = n.radius;
  b.mu = std::sqrt(n.mu2);
  b.delta = std::sqrt(n.delta2);
  const float length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (int k = 0; k < 3; ++k) b.axis[k] = axis[k] / length;
  b.cone_angle = angle;
  return node_criteria(n.p, b);
}

TEST(Criteria, SphereOutsideTheFrustumIsNotRefined) {
  const ViewCriteria view = make_criteria(test_view(), 1);
  EXPECT_FALSE(outside_frustum(view, node_at(0, 0, 0, 0.1f)));
  EXPECT_TRUE(outside_frustum(view, node_at(100, 0, 0, 1)));    // far to the right
  EXPECT_TRUE(outside_frustum(view, node_at(0, 0, 10, 1)));     // behind the eye
  EXPECT_TRUE(outside_frustum(view, node_at(0, -50, 0, 1)));    // below
  EXPECT_FALSE(outside_frustum(view, node_at(100, 0, 0, 99)));  // a big sphere reaching into view
  // The half-width of the view at the origin is 5 tan(22.5°) * 4/3; a sphere just past it but touching.
  const float edge = 5 * std::tan(22.5f * kPi / 180) * 4.0f / 3.0f;
  EXPECT_FALSE(outside_frustum(view, node_at(edge + 0.09f, 0, 0, 0.1f)));
  EXPECT_TRUE(outside_frustum(view, node_at(edge + 0.2f, 0, 0, 0.1f)));
  // qrefine: a big error does not help a node out of view.
  EXPECT_FALSE(qrefine(view, node_at(100, 0, 0, 1, 10, 10)));
  EXPECT_TRUE(qrefine(view, node_at(0, 0, 0, 1, 10, 10)));
}

TEST(Criteria, BackFacingConeIsNotRefined) {
  const ViewCriteria view = make_criteria(test_view(), 0);
  const float away[3] = {0, 0, -1}, toward[3] = {0, 0, 1}, side[3] = {1, 0, 0};
  const NodeCriteria base = node_at(0, 0, 0, 0.1f, 1, 1);
  EXPECT_TRUE(back_facing(view, with_cone(base, away, 0.2f)));
  EXPECT_FALSE(qrefine(view, with_cone(base, away, 0.2f)));
  EXPECT_FALSE(back_facing(view, with_cone(base, toward, 0.2f)));
  EXPECT_TRUE(qrefine(view, with_cone(base, toward, 0.2f)));
  EXPECT_FALSE(back_facing(view, with_cone(base, side, 0.01f)));    // silhouette
  EXPECT_FALSE(back_facing(view, with_cone(base, away, kPi / 2)));  // a half-space of normals
  EXPECT_FALSE(back_facing(view, with_cone(base, away, kPi)));
  // Hoppe's test without the radius: the axis points away from the eye (a·d > 0 with α = 0), but the
  // sphere reaches where that face plane would be seen from the front.
  const float tilted[3] = {1, 0, -0.2f};
  const NodeCriteria big = with_cone(node_at(0, 0, 0, 1.5f, 1, 1), tilted, 0);
  const float d[3] = {0, 0, -5};  // p - e
  const float along = (tilted[0] * d[0] + tilted[1] * d[1] + tilted[2] * d[2]) / std::sqrt(1.04f);
  EXPECT_GT(along, 0) << "Hoppe's r = 0 test would cull this node";
  EXPECT_FALSE(back_facing(view, big));
  // ... and a face at (-1.5, 0, 0) with that normal is indeed front-facing.
  const float q[3] = {-1.5f, 0, 0};
  EXPECT_LT((tilted[0] * (q[0] - 0) + tilted[2] * (q[2] - 5)), 0);
}

// Sampled: whenever some point of the sphere with some normal of the cone faces the eye, the node is not
// culled (conservative culling never drops a visible face).
TEST(Criteria, BackFaceCullingIsConservative) {
  const ViewCriteria view = make_criteria(test_view(), 0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1, 1), positive(0, 1);
  size_t culled = 0, visible = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const float p[3] = {unit(rng), unit(rng), unit(rng)};
    float axis[3] = {unit(rng), unit(rng), unit(rng) - 0.7f};
    const float length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (length < 0.1f) continue;
    for (float& a : axis) a /= length;
    const float radius = 0.5f * positive(rng) * positive(rng), angle = 1.4f * positive(rng) * positive(rng);
    const NodeCriteria node = with_cone(node_at(p[0], p[1], p[2], radius, 1, 1), axis, angle);
    const bool cull = back_facing(view, node);
    culled += cull;
    // Sample the sphere's surface and the cone's boundary (where the extremes lie).
    bool seen = false;
    for (int s = 0; s < 200 && !seen; ++s) {
      float w[3] = {unit(rng), unit(rng), unit(rng)};
      const float wl = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
      float o[3] = {unit(rng), unit(rng), unit(rng)};  // a direction orthogonal to the axis
      const float oa = o[0] * node.axis[0] + o[1] * node.axis[1] + o[2] * node.axis[2];
      for (int k = 0; k < 3; ++k) o[k] -= oa * node.axis[k];
      const float ol = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
      if (wl < 1e-3f || ol < 1e-3f) continue;
      float n[3], q[3];
      for (int k = 0; k < 3; ++k) {
        n[k] = std::cos(angle) * node.axis[k] + std::sin(angle) * o[k] / ol;
        q[k] = p[k] + radius * w[k] / wl;
      }
      seen = n[0] * (view.eye[0] - q[0]) + n[1] * (view.eye[1] - q[1]) + n[2] * (view.eye[2] - q[2]) > 0;
    }
    visible += seen;
    if (seen) {
      ASSERT_FALSE(cull) << "trial " << trial << ": a front-facing sample was culled";
    }
  }
  EXPECT_GT(culled, 200u);  // the test does cull, often
  EXPECT_GT(visible, 200u);
}

// mu projects to mu / (distance * pixel_angle) pixels: refined exactly while that exceeds τ.
TEST(Criteria, ScreenErrorThresholdIsMonotoneInDistanceAndTolerance) {
  const ViewParams params = test_view(45, 800, 600);
  const float mu = 0.01f;
  for (float tau : {0.5f, 1.0f, 4.0f}) {
    const ViewCriteria view = make_criteria(params, tau);
    const float limit = mu / (tau * params.pixel_angle);  // distance at which mu covers τ pixels
    bool previous = true;
    for (float z = 4.9f; z > -200; z -= 0.37f) {
      const NodeCriteria node = node_at(0, 0, z, 0.001f, mu, 0);
      const float distance = 5 - z;
      const bool refine = screen_error_exceeds(view, node);
      EXPECT_TRUE(previous || !refine) << "refines again farther away at z = " << z;
      previous = refine;
      if (distance < limit * 0.999f) {
        EXPECT_TRUE(refine) << tau << " " << distance;
      }
      if (distance > limit * 1.001f) {
        EXPECT_FALSE(refine) << tau << " " << distance;
      }
    }
  }
  // Larger τ never refines where a smaller one did not.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(-1, 1), positive(0, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const NodeCriteria node =
        node_at(unit(rng), unit(rng), unit(rng) * 20, 0.01f, 0.02f * positive(rng), 0.05f * positive(rng));
    const float a = 3 * positive(rng), b = a + 3 * positive(rng);
    if (screen_error_exceeds(make_criteria(params, b), node)) {
      ASSERT_TRUE(screen_error_exceeds(make_criteria(params, a), node));
    }
  }
}

// delta counts by how much of it is seen across the line of sight: along it, not at all.
TEST(Criteria, DeltaCountsAcrossTheLineOfSight) {
  const ViewParams params = test_view();
  const ViewCriteria view = make_criteria(params, 1);
  const float facing[3] = {0, 0, 1}, across[3] = {1, 0, 0};
  const float delta = 0.05f;  // 0.05 / (5 * pixel_angle) ~ 14.5 px
  EXPECT_FALSE(screen_error_exceeds(view, with_cone(node_at(0, 0, 0, 0.01f, 0, delta), facing, kPi)));
  EXPECT_TRUE(screen_error_exceeds(view, with_cone(node_at(0, 0, 0, 0.01f, 0, delta), across, kPi)));
}

TEST(Criteria, LeavesNeverRefineEvenAtZeroTolerance) {
  const ViewCriteria view = make_criteria(test_view(), 0);
  EXPECT_FALSE(qrefine(view, node_at(0, 0, 0, 0.1f, 0, 0)));
  EXPECT_TRUE(qrefine(view, node_at(0, 0, 0, 0.1f, 1e-6f, 0)));
  EXPECT_THROW(make_criteria(test_view(), -1), Error);
  EXPECT_THROW(make_criteria(test_view(), NAN), Error);

  // What the builder stores for leaves decodes to mu = delta = 0.
  const BuildResult built = build_progressive_mesh(make_sphere(12, 16));
  const Hierarchy& h = built.hierarchy;
  size_t leaves = 0, internal_with_error = 0;
  for (uint32_t n = 0; n < h.node_count(); ++n) {
    const RefineBounds b = dequantize_refine(h.refine[n], h.scale);
    if (h.is_leaf(n)) {
      ++leaves;
      EXPECT_EQ(b.mu, 0.0f);
      EXPECT_EQ(b.delta, 0.0f);
      EXPECT_GT(b.radius, 0.0f);
      const float* p = &h.position[3 * size_t(n)];
      EXPECT_FALSE(qrefine(view, p, b));
    } else {
      internal_with_error += b.mu > 0 || b.delta > 0;
    }
  }
  EXPECT_EQ(leaves, h.leaf_count());
  EXPECT_GT(internal_with_error, 0u);
}

}  // namespace
}  // namespace pms
