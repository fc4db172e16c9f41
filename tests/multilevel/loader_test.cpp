// addLevel (multilevel/loader.h): levels added coarsest first give, after each, the LODs of the
// whole mesh down to that level, and after the last the whole mesh; hostile pieces are refused by name.
#include <gtest/gtest.h>
#include <algorithm>
#include <cstring>
#include <functional>
#include <string>

#include "common/error.h"
#include "error_of.h"
#include "fixtures/view_models.h"
#include "multilevel/build.h"
#include "multilevel/loader.h"
#include "multilevel/mesh.h"

namespace pms {
namespace {

const MultilevelMesh& terrain_levels() {
  static const MultilevelMesh m = [] {
    const test::BuiltModel& model = test::built_terrain();
    return build_multilevel(model.input, collapses_of(model.h), 10);
  }();
  return m;
}

using test::error_of;

TEST(MultilevelLoader, EveryLoadedLodIsTheWholeMeshsAndTheLastLevelGivesTheMesh) {
  const MultilevelMesh& m = terrain_levels();
  const MultilevelParts parts = multilevel_parts(m);
  MultilevelLoader loader("test", parts.head);
  MultilevelLod whole(m);
  for (const auto& level : parts.levels) {
    loader.add_level("test", level);
    MultilevelLod partial(loader.mesh());
    for (uint32_t l = loader.finest_loaded(); l < m.level_count(); ++l) {
      partial.set_level(l);
      whole.set_level(l);
      EXPECT_TRUE(std::equal(partial.indices().begin(), partial.indices().end(), whole.indices().begin(),
                             whole.indices().end()))
          << "LOD " << l << " with levels down to " << loader.finest_loaded();
      if (l + 1 < m.level_count()) {
        partial.set_level(float(l) + 0.5f);
        whole.set_level(float(l) + 0.5f);
        EXPECT_TRUE(std::equal(partial.positions().begin(), partial.positions().end(), whole.positions().begin(),
                               whole.positions().end()));
      }
    }
    partial.set_level(0u);  // a level not loaded yet shows the finest loaded
    EXPECT_EQ(partial.indices().size(), size_t(3) * m.triangle_count[loader.finest_loaded()]);
  }
  ASSERT_TRUE(loader.complete());
  const MultilevelMesh got = loader.release();
  EXPECT_EQ(got.positions, m.positions);
  EXPECT_EQ(got.triangles, m.triangles);
  EXPECT_EQ(got.representative, m.representative);
  EXPECT_EQ(got.vertex_count, m.vertex_count);
  EXPECT_EQ(got.triangle_count, m.triangle_count);
}

TEST(MultilevelLoader, HostilePiecesAreRefusedByName) {
  const MultilevelMesh& m = terrain_levels();
  const MultilevelParts parts = multilevel_parts(m);
  const uint32_t top = m.level_count() - 1;
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", std::vector<uint8_t>(31)); }),
            "h: section HEAD: 31 bytes (32 expected)");
  auto head = parts.head;
  const uint32_t huge = 0x7FFFFFFF;
  std::memcpy(head.data() + 12, &huge, 4);
  EXPECT_NE(error_of([&] { MultilevelLoader("h", head); }).find("over the limit"), std::string::npos);

  MultilevelLoader out_of_order("h", parts.head);
  EXPECT_EQ(
      error_of([&] { out_of_order.add_level("l", parts.levels[1]); }),
      "l: offset 0: section LEVL of level " + std::to_string(top) + ": says it is level " + std::to_string(top - 1));
  MultilevelLoader truncated("h", parts.head);
  auto cut = parts.levels[0];
  cut.resize(cut.size() - 4);
  EXPECT_NE(error_of([&] { truncated.add_level("l", cut); }).find("words but its counts need"), std::string::npos);
  // The last representative pair of a level that states several made a copy of the one before it.
  size_t with_reps = 0;
  uint32_t header[4] = {0, 0, 0, 0};
  for (; with_reps < parts.levels.size(); ++with_reps) {
    std::memcpy(header, parts.levels[with_reps].data(), 16);
    if (header[3] >= 2) break;
  }
  ASSERT_LT(with_reps, parts.levels.size());
  MultilevelLoader twice("h", parts.head);
  for (size_t i = 0; i < with_reps; ++i) twice.add_level("l", parts.levels[i]);
  auto repeated = parts.levels[with_reps];
  std::memcpy(repeated.data() + repeated.size() - 8, repeated.data() + repeated.size() - 16, 8);
  EXPECT_NE(error_of([&] { twice.add_level("l", repeated); }).find("two representatives"), std::string::npos);
  MultilevelLoader done("h", parts.head);
  for (const auto& level : parts.levels) done.add_level("l", level);
  EXPECT_EQ(error_of([&] { done.add_level("l", parts.levels.back()); }),
            "l: more LEVL sections than HEAD's " + std::to_string(m.level_count()) + " levels");
}

}  // namespace
}  // namespace pms
