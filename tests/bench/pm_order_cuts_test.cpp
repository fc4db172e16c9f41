// What issue 19's work item (a) would save (docs/internals.md, "Split records"): the records' topology bits
// when each split names, instead of its fundamental cut vertices (leaves), their active ancestors in the
// PM-order mesh at the moment v_s splits (kim-lee-kobbelt's v_l, v_r in the original sequence), which is
// as deep as a record needs to go if the client resolves the rest in its own neighbourhood.
// PMSTREAM_RECORD_BITS_PMS=FILE.pms measures that file, else the bunny.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

#include "bench/split_record_bits.h"
#include "builder/build.h"
#include "io/mesh.h"
#include "record_bits_model.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/split_codec.h"
#include "test_support.h"

namespace pms::bench {
namespace {

// The ancestor of `leaf` active when the split at `time` (its index in the split order) happens.
uint32_t active_at(const ModelData& model, const std::vector<uint64_t>& split_time, uint32_t leaf, uint64_t time) {
  uint32_t n = leaf;
  for (;;) {
    const uint32_t p = model.parent[n];
    if (p == kNone || split_time[p] < time) return n;  // n exists (root or made before) and is not split yet
    n = p;
  }
}

void measure(const char* name, const ModelData& model) {
  const size_t n = model.node_count();
  std::vector<uint64_t> split_time(n, UINT64_MAX);
  for (size_t i = 0; i < model.split_order.size(); ++i) split_time[model.split_order[i]] = i;
  std::vector<uint32_t> cut_left(model.cut_left.begin(), model.cut_left.end()),
      cut_right(model.cut_right.begin(), model.cut_right.end());
  uint64_t levels = 0, cuts = 0;
  for (uint32_t node = 0; node < n; ++node) {
    if (model.is_leaf(node)) continue;
    for (std::vector<uint32_t>* side : {&cut_left, &cut_right}) {
      uint32_t& cut = (*side)[node];
      if (cut == kNone) continue;
      const uint32_t active = active_at(model, split_time, cut, split_time[node]);
      ASSERT_FALSE(is_ancestor_or_self(model.id(node), model.id(active)));
      levels += uint64_t(model.id(cut).depth() - model.id(active).depth());
      ++cuts;
      cut = active;
    }
  }
  ModelData pm_order = model;
  pm_order.cut_left = cut_left;
  pm_order.cut_right = cut_right;
  const std::vector<uint32_t> q = grid_positions(model, 16);
  const std::vector<uint32_t> close = splits_for_view(model, close_view(model), 1.0f);
  const ModelData* models[] = {&model, &pm_order};
  for (const ModelData* m : models) {
    const SplitCodec codec = SplitCodec::build(*m, q, 16);
    const RecordBitsReport whole = record_bits(*m, codec, q, m->split_order);
    const RecordBitsReport view = record_bits(*m, codec, q, close);
    std::printf("%s, %s cut vertices: topology %.2f bits per split (whole model), %.2f (E5 close view)\n", name,
                m == &model ? "fundamental" : "PM-order", whole.per_split(whole.bits.topology),
                view.per_split(view.bits.topology));
  }
  std::printf("%s: the PM-order cut vertex is %.2f levels above the fundamental one on average\n", name,
              double(levels) / double(cuts));
  EXPECT_GT(cuts, 0u);
}

TEST(PmOrderCuts, TopologyBitsAgainstFundamentalCuts) { PMS_MEASURE_RECORD_BITS_MODEL(measure); }

}  // namespace
}  // namespace pms::bench
