// The sender-driven session's coded front (server/compact_front.h): any front of the forest comes back as
// the same active tags, in about two bits per node, and a session parked that way answers as one that keeps
// windowed tags throughout.
#include <gtest/gtest.h>
#include <random>
#include <vector>

#include "builder/build.h"
#include "io/shapes.h"
#include "server/compact_front.h"
#include "spm/hierarchy.h"

namespace pms {
namespace {

std::vector<uint32_t> active_nodes(const ActiveTags& tags) {
  std::vector<uint32_t> nodes;
  for (uint32_t v = tags.next_active(0); v != UINT32_MAX; v = tags.next_active(v + 1)) nodes.push_back(v);
  return nodes;
}

TEST(CompactFront, AnyFrontComesBackAsTheSameTags) {
  const BuildResult built = build_progressive_mesh(make_terrain(20000, 3), BuildOptions{});
  const ModelData model = model_of(built.hierarchy);
  std::mt19937 rng(11);
  ActiveTags tags(model.root_count);
  uint64_t splits = 0;
  for (int round = 0; round < 40; ++round) {
    // Refine a random share of the front, as VIEW answers do: the front only moves down.
    const std::vector<uint32_t> front = active_nodes(tags);
    for (uint32_t v : front)
      if (!model.is_leaf(v) && rng() % 3 == 0) {
        tags.split(v, model.first_child[v]);
        ++splits;
      }
    const CompactFront compact(model, tags);
    ASSERT_EQ(compact.active_count(), tags.active_count());
    ASSERT_EQ(compact.code_bits(), model.root_count + 2 * splits) << "a bit per root, two per split node";
    EXPECT_LE(compact.memory_bytes(), (compact.code_bits() + 63) / 64 * 8);
    const ActiveTags back = compact.tags(model);
    ASSERT_EQ(active_nodes(back), active_nodes(tags));
    ASSERT_EQ(back.active_count(), tags.active_count());
  }
  EXPECT_GT(splits, 1000u) << "the fronts stayed coarse: the test proves little";
}

TEST(CompactFront, RefusesTagsThatAreNotAFront) {
  const BuildResult built = build_progressive_mesh(make_sphere(12, 16), BuildOptions{});
  const ModelData model = model_of(built.hierarchy);
  ActiveTags gap(model.root_count);
  gap.deactivate(0);  // root 0's tree has no front node at all
  EXPECT_THROW(CompactFront(model, gap), std::logic_error);
  ActiveTags doubled(model.root_count);
  uint32_t internal = 0;
  while (model.is_leaf(internal)) ++internal;
  doubled.activate(model.first_child[internal]);  // a node below an active one
  EXPECT_THROW(CompactFront(model, doubled), std::logic_error);
}

}  // namespace
}  // namespace pms
