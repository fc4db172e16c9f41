// A receiver-driven request's ids resolved to model nodes (server/split_lookup.h): the same nodes as a walk
// from the root for each id, in any order of the ids, with each id's descendants breadth-first, and bad_id
// for what the model lacks.
#include <gtest/gtest.h>
#include <algorithm>
#include <random>
#include <vector>

#include "builder/build.h"
#include "io/shapes.h"
#include "protocol/message_types.h"
#include "protocol/split_request.h"
#include "server/split_lookup.h"
#include "spm/hierarchy.h"

namespace pms {
namespace {

using protocol::ErrorCode;
using protocol::ProtocolError;
using protocol::SplitRequest;

class SplitLookup : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    built_ = new Hierarchy(build_progressive_mesh(make_sphere(40, 60), BuildOptions{}).hierarchy);
  }
  static void TearDownTestSuite() { delete built_; }

  const ModelData model = model_of(*built_);

  // `count` distinct internal nodes none of which is an ancestor of another, as ids.
  std::vector<VertexId> random_antichain(std::mt19937& random, size_t count) const {
    std::vector<VertexId> ids;
    std::uniform_int_distribution<uint32_t> pick(0, uint32_t(model.node_count() - 1));
    for (int attempts = 0; ids.size() < count && attempts < 100000; ++attempts) {
      const uint32_t n = pick(random);
      if (model.is_leaf(n)) continue;
      const VertexId id = model.id(n);
      if (std::any_of(ids.begin(), ids.end(),
                      [&](VertexId o) { return is_ancestor_or_self(o, id) || is_ancestor_or_self(id, o); }))
        continue;
      ids.push_back(id);
    }
    return ids;
  }

  // What requested_nodes must give: each id found from its root, its internal descendants level by level.
  std::vector<uint32_t> expected(const SplitRequest& request) const {
    std::vector<uint32_t> nodes;
    for (const VertexId id : request.ids) {
      std::vector<uint32_t> level{model.find(id)};
      for (uint32_t depth = 0; depth <= request.depth && !level.empty(); ++depth) {
        nodes.insert(nodes.end(), level.begin(), level.end());
        std::vector<uint32_t> next;
        for (const uint32_t n : level)
          for (uint32_t c = 0; c < 2; ++c)
            if (!model.is_leaf(model.first_child[n] + c)) next.push_back(model.first_child[n] + c);
        level = std::move(next);
      }
    }
    return nodes;
  }

  static ErrorCode error_of(const ModelData& model, const SplitRequest& request) {
    try {
      server::requested_nodes(model, request, 1u << 20);
    } catch (const ProtocolError& e) {
      return e.code;
    }
    ADD_FAILURE() << "no error";
    return ErrorCode::internal;
  }

  static Hierarchy* built_;
};

Hierarchy* SplitLookup::built_ = nullptr;

TEST_F(SplitLookup, FindsTheNodesAWalkFromTheRootFindsInCodeOrderAndAnyOther) {
  std::mt19937 random(19);
  for (int trial = 0; trial < 200; ++trial) {
    SplitRequest request{uint32_t(trial % 3), random_antichain(random, 1 + trial % 97)};
    if (trial % 2 == 0) std::sort(request.ids.begin(), request.ids.end(), protocol::code_order);
    ASSERT_EQ(server::requested_nodes(model, request, 1u << 20), expected(request)) << "trial " << trial;
  }
}

TEST_F(SplitLookup, AnIdTheModelLacksOrALeafIsABadIdWhereverItComes) {
  std::mt19937 random(7);
  uint32_t leaf = 0;
  while (!model.is_leaf(leaf)) ++leaf;
  const VertexId leaf_id = model.id(leaf);
  const VertexId below_leaf{leaf_id.tree, leaf_id.node << 1};
  for (const VertexId bad : {leaf_id, below_leaf, VertexId{model.root_count, 1}}) {
    for (size_t at : {size_t(0), size_t(5), size_t(20)}) {
      SplitRequest request{0, random_antichain(random, 20)};
      std::erase_if(request.ids,
                    [&](VertexId id) { return is_ancestor_or_self(id, bad) || is_ancestor_or_self(bad, id); });
      request.ids.insert(request.ids.begin() + std::min(at, request.ids.size()), bad);
      EXPECT_EQ(error_of(model, request), ErrorCode::bad_id) << to_string(bad) << " at " << at;
    }
  }
}

TEST_F(SplitLookup, AnAnswerOverTheLimitIsTooLarge) {
  std::mt19937 random(3);
  const SplitRequest request{2, random_antichain(random, 50)};
  const size_t count = expected(request).size();
  EXPECT_EQ(server::requested_nodes(model, request, uint32_t(count)).size(), count);
  try {
    server::requested_nodes(model, request, uint32_t(count - 1));
    ADD_FAILURE() << "no error";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(e.code, ErrorCode::too_large);
  }
}

}  // namespace
}  // namespace pms
