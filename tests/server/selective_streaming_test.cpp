// Windowed active tags and SelectiveStreaming: the server's bookkeeping matches a plain set, and every
// batch it decides is applicable, in order, by a client that knows only what it was sent.
#include <gtest/gtest.h>
#include <algorithm>
#include <random>
#include <set>

#include "builder/build.h"
#include "io/shapes.h"
#include "server/selective_streaming.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

TEST(ActiveTags, MatchesASetUnderRandomOperations) {
  std::mt19937 rng(7);
  ActiveTags tags(100);
  std::set<uint32_t> reference;
  for (uint32_t i = 0; i < 100; ++i) reference.insert(i);
  for (int step = 0; step < 20000; ++step) {
    // Drift right like a refining front: deactivate low nodes, activate higher ones.
    const uint32_t base = uint32_t(step / 4);
    const uint32_t node = base + std::uniform_int_distribution<uint32_t>(0, 300)(rng);
    if (rng() % 2) {
      tags.activate(node);
      reference.insert(node);
    } else {
      tags.deactivate(node);
      reference.erase(node);
    }
    if (step % 97 == 0) {
      ASSERT_EQ(tags.active_count(), reference.size());
      if (!reference.empty()) {
        ASSERT_EQ(tags.win_min(), *reference.begin());
        ASSERT_EQ(tags.win_max(), *reference.rbegin());
      }
      std::vector<uint32_t> walked;
      for (uint32_t v = tags.next_active(0); v != UINT32_MAX; v = tags.next_active(v + 1)) walked.push_back(v);
      ASSERT_EQ(walked, std::vector<uint32_t>(reference.begin(), reference.end()));
    }
  }
  // The window followed the front: memory is bounded by the window, not by the highest index seen.
  EXPECT_LE(tags.memory_bytes(), 4 * ((tags.win_max() - tags.win_min()) / 8 + 64));
}

struct Client {
  explicit Client(const ModelData& model)
      : hierarchy(VertexHierarchy::from_model(model)), mesh(hierarchy, model.base_faces) {}
  VertexHierarchy hierarchy;
  SelectiveMesh mesh;
};

// Sends `batch` to a client: each packet is attached, then split right away; the server ordered the
// batch so every forced split is already known.
void deliver(const ModelData& model, const std::vector<uint32_t>& batch, Client& client) {
  for (uint32_t node : batch) {
    client.hierarchy.add_split(split_record(model, node));
    const uint32_t slot = client.hierarchy.find(model.id(node));
    ASSERT_NE(slot, kNone);
    if (!client.mesh.is_active(slot)) continue;  // already split as part of a forced chain
    const VSplitResult r = client.mesh.vsplit(slot);
    ASSERT_TRUE(r.done) << "split of " << to_string(model.id(node)) << " needs an unsent packet";
  }
}

TEST(SelectiveStreaming, BatchesApplyInOrderAndTheFrontMatchesTheServer) {
  const BuildResult built = build_progressive_mesh(make_terrain(20000, 3), BuildOptions{});
  const ModelData model = model_of(built.hierarchy);
  const DependencyFilter dependencies(model);
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    ActiveTags tags(model.root_count), tags_from_leaves(model.root_count);
    Client client(model);
    std::vector<uint32_t> batch, batch_from_leaves;
    // Views as pseudo-random predicates: each VIEW wants a different region, with varying importance.
    for (uint32_t view = 0; view < 6; ++view) {
      const uint32_t salt = seed * 131 + view;
      const Importance importance = [&](uint32_t node) {
        const uint32_t h = (node * 2654435761u) ^ salt;
        return (h % 5 < 2) ? float(h % 1000 + 1) : 0.0f;
      };
      batch.clear();
      ASSERT_TRUE(selective_streaming(model, dependencies, tags, importance, SIZE_MAX, batch));
      // Skipping the partial-order checks that cannot fire changes what a split costs, never the answer.
      batch_from_leaves.clear();
      ASSERT_TRUE(
          selective_streaming(model, DependencyFilter(), tags_from_leaves, importance, SIZE_MAX, batch_from_leaves));
      ASSERT_EQ(batch, batch_from_leaves);
      deliver(model, batch, client);
      EXPECT_FALSE(batch.empty()) << "view " << view << " sent nothing";
      std::string why;
      ASSERT_TRUE(client.mesh.check_invariants(&why)) << why;
    }
    // The server's front is exactly the leaves of what the client knows.
    for (uint32_t node = 0; node < model.node_count(); ++node) {
      const uint32_t slot = client.hierarchy.find(model.id(node));
      const bool known_leaf = slot != kNone && client.hierarchy.is_leaf(slot);
      ASSERT_EQ(tags.is_active(node), known_leaf) << to_string(model.id(node));
    }
  }
}

TEST(SelectiveStreaming, EverythingWantedStreamsTheWholeModelOnce) {
  const BuildResult built = build_progressive_mesh(make_sphere(24, 32), BuildOptions{});
  const ModelData model = model_of(built.hierarchy);
  ActiveTags tags(model.root_count);
  Client client(model);
  std::vector<uint32_t> batch;
  const Importance everything = [](uint32_t) { return 1.0f; };
  // In bounded slices, as a server does per VIEW; the last step reports the view served.
  SelectiveStreamer streamer;
  const DependencyFilter dependencies(model);
  streamer.start(model, dependencies, tags, everything);
  bool served = false;
  constexpr uint64_t kBudget = 64;
  uint64_t most_work = 0;
  for (int call = 0; call < 100000 && !served; ++call) {
    const size_t before = batch.size();
    uint64_t work = 0;
    served = streamer.step(100, kBudget, batch, work);
    ASSERT_LE(batch.size() - before, 100u);
    most_work = std::max(most_work, work);
    deliver(model, std::vector<uint32_t>(batch.begin() + ptrdiff_t(before), batch.end()), client);
  }
  ASSERT_TRUE(served);
  // A slice ends within one dependency chain (its splits and their children's evaluations) of the budget.
  EXPECT_LE(most_work, kBudget + 3 * 64);
  EXPECT_EQ(batch.size(), model.split_order.size());
  EXPECT_EQ(std::set<uint32_t>(batch.begin(), batch.end()).size(), batch.size()) << "a split was sent twice";
  EXPECT_EQ(client.mesh.face_count(), built.stats.input_faces);
  EXPECT_EQ(tags.active_count(), built.stats.input_vertices);
  // A second pass finds nothing to send.
  const size_t total = batch.size();
  EXPECT_TRUE(selective_streaming(model, dependencies, tags, everything, SIZE_MAX, batch));
  EXPECT_EQ(batch.size(), total);
}

}  // namespace
}  // namespace pms
