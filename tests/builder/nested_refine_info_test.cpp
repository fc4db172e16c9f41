// Nested refinement info (builder/nested_refine_info.h) on bunny: every node's nested bounds hold its own
// (the same sphere or larger, a cone that contains its own cone, a deviation space at least its own
// re-expressed about the moved axis), and nearly every child's values are lattice entries below its
// parent's, which is what makes them cheap in a split record.
#include <gtest/gtest.h>

#include <cmath>

#include "builder/build.h"
#include "io/mesh.h"
#include "spm/nested_info.h"
#include "spm/refine_info.h"
#include "test_support.h"

namespace pms {
namespace {

double angle(const float* a, const float* b) {
  const double cx = double(a[1]) * b[2] - double(a[2]) * b[1], cy = double(a[2]) * b[0] - double(a[0]) * b[2],
               cz = double(a[0]) * b[1] - double(a[1]) * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz),
                    double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]);
}

TEST(NestedRefineInfo, BunnyBoundsHoldTheirOwnAndNestInTheirParents) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  Mesh mesh = load_mesh(path.string());
  clean_mesh(mesh);
  BuildOptions unnested;
  unnested.nested_info = false;
  const Hierarchy own = build_progressive_mesh(mesh, unnested).hierarchy;
  const Hierarchy h = build_progressive_mesh(mesh).hierarchy;
  ASSERT_EQ(h.node_count(), own.node_count());
  size_t lengths = 0, entries = 0, cones = 0, snapped = 0;
  for (uint32_t n = 0; n < h.node_count(); ++n) {
    // The same build, the same ids (the packing within a level follows the deviation, so indices differ).
    const uint32_t m = own.find(h.id(n));
    ASSERT_NE(m, kNone);
    const RefineInfo& a = own.refine[m];
    const RefineInfo& b = h.refine[n];
    if (n < h.root_count || never_refines(a)) {
      EXPECT_EQ(a, b) << "node " << n;
      continue;
    }
    const RefineBounds x = dequantize_refine(a, 1), y = dequantize_refine(b, 1);
    EXPECT_GE(y.radius, x.radius) << "node " << n;
    EXPECT_GE(y.mu, x.mu) << "node " << n;
    EXPECT_GE(y.delta, x.delta) << "node " << n;  // mu and delta only grow when the axis moves
    if (b.cone_angle != kNoCone) {
      ASSERT_NE(a.cone_angle, kNoCone) << "node " << n;
      EXPECT_LE(angle(x.axis, y.axis) + x.cone_angle, double(y.cone_angle) + 1e-6) << "node " << n;
      // On the coarse grid, unless moving there would open the cone to pi/2 (then it stays).
      const bool moved = b.cone_x != a.cone_x || b.cone_y != a.cone_y;
      snapped += int16_t(b.cone_x) % (1 << kAxisSnapBits) == 0 && int16_t(b.cone_y) % (1 << kAxisSnapBits) == 0;
      ++cones;
      if (moved) {
        EXPECT_EQ(int16_t(b.cone_x) % (1 << kAxisSnapBits), 0);
        EXPECT_EQ(int16_t(b.cone_y) % (1 << kAxisSnapBits), 0);
      }
    }
    const RefineInfo parent = as_sent(h.refine[h.parent[n]]);
    const uint32_t steps[3] = {kRadiusCodesPerStep, kMuCodesPerStep, kDeltaCodesPerStep};
    const uint16_t RefineInfo::*fields[3] = {&RefineInfo::radius, &RefineInfo::mu, &RefineInfo::delta};
    for (int f = 0; f < 3; ++f) {
      ++lengths;
      const uint32_t k = length_entry(parent.*fields[f], b.*fields[f], steps[f]);
      entries +=
          b.*fields[f] == 0 || (k != kNoEntry && length_at_entry(parent.*fields[f], k, steps[f]) == b.*fields[f]);
    }
  }
  EXPECT_GT(double(entries), 0.99 * double(lengths));
  EXPECT_GT(double(snapped), 0.99 * double(cones));
}

}  // namespace
}  // namespace pms
