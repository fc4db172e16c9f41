// The deviation space (Hoppe 1997 §4.3) is what τ = 0 px reads: a node may stay coarse at τ = 0 only
// when its collapse changed no surface. Measured at the leaf positions alone, a flat vertex next to a
// stud looks free to collapse (it lies on the coarse surface, its faces up the stud do not), and τ = 0
// left a visible facet there.
#include <gtest/gtest.h>
#include <algorithm>

#include "fixtures/view_models.h"
#include "spm/selective_mesh.h"

namespace pms {
namespace {

class DeviationMeasure : public ::testing::TestWithParam<pms::Deviation> {};

TEST_P(DeviationMeasure, ZeroToleranceKeepsEveryFaceThatLeavesThePlane) {
  const test::BuiltModel& model = test::built_studded_plane(GetParam());
  const test::RefinedFromAbove refined(model);
  const SelectiveMesh& mesh = refined.mesh;
  const auto kept = test::leaf_input_faces(mesh, model);
  const Mesh& input = model.input;
  size_t off_plane = 0;
  for (size_t i = 0; i < input.indices.size(); i += 3) {
    std::array<uint32_t, 3> face{input.indices[i], input.indices[i + 1], input.indices[i + 2]};
    const bool flat =
        std::all_of(face.begin(), face.end(), [&](uint32_t v) { return input.positions[3 * size_t(v) + 2] == 0; });
    if (flat) continue;
    ++off_plane;
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    EXPECT_TRUE(std::binary_search(kept.begin(), kept.end(), face))
        << "input face " << i / 3 << " on a stud is missing";
  }
  EXPECT_GT(off_plane, 0u);
  EXPECT_LT(mesh.face_count(), input.face_count()) << "the flat part should stay coarse";
}

INSTANTIATE_TEST_SUITE_P(BothMeasures, DeviationMeasure,
                         ::testing::Values(pms::Deviation::bound, pms::Deviation::estimate),
                         [](const auto& info) { return info.param == pms::Deviation::bound ? "bound" : "estimate"; });

}  // namespace
}  // namespace pms
