// Table 2's replay (bench/topology_schemes.h): the PM-order replay ends on the same faces the refinement
// engine makes from the whole split order, every split's fields are those of the mesh it applies to, and
// each scheme's bits follow from its fields.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <span>

#include "bench/topology_schemes.h"
#include "protocol/model_messages.h"
#include "record_bits_model.h"
#include "spm/stream_order.h"

namespace pms::bench {
namespace {

using Point = std::array<float, 3>;
using Face = std::array<Point, 3>;

// Faces as corner positions, each rotated to start at its smallest corner (keeps the orientation), sorted:
// the engine numbers its vertices by slot, the replay by node.
std::vector<Face> canonical(std::span<const float> positions, const std::vector<uint32_t>& corners) {
  const auto point = [&](uint32_t v) { return Point{positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; };
  std::vector<Face> faces;
  for (size_t i = 0; i + 2 < corners.size(); i += 3) {
    Face f = {point(corners[i]), point(corners[i + 1]), point(corners[i + 2])};
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    faces.push_back(f);
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

void check_replay(const char*, const ModelData& model) {
  uint64_t splits = 0, neighbours = 0, boundary = 0, missing_sides = 0;
  bool fields_ok = true;
  const std::vector<uint32_t> replayed = replay_pm_topology(model, [&](const SplitTopology& s) {
    ++splits;
    neighbours += s.neighbours.size();
    fields_ok &= s.vt == model.first_child[s.vs];
    fields_ok &= (s.vl == kNone) == (model.cut_left[s.vs] == kNone) && (s.fl == kNone) == (s.vl == kNone);
    fields_ok &= (s.vr == kNone) == (model.cut_right[s.vs] == kNone) && (s.fr == kNone) == (s.vr == kNone);
    fields_ok &= s.vl == kNone || s.neighbours.front() == s.vl;  // N(v_s) lists the cut vertices first
    fields_ok &= s.min_id <= s.max_id;
    boundary += s.vl == kNone || s.vr == kNone;
    missing_sides += (s.vl == kNone) + (s.vr == kNone);
  });
  EXPECT_TRUE(fields_ok);
  EXPECT_EQ(splits, model.split_order.size());

  const MeshArrays engine = refine_in_stream_order(model, model.split_order.size());
  EXPECT_TRUE(canonical(model.position, replayed) == canonical(engine.positions, engine.indices))
      << "the replay and the engine made different meshes";

  const double valence = double(neighbours) / double(splits);
  EXPECT_GT(valence, 4.0);
  EXPECT_LT(valence, 9.0);
  std::printf("%llu splits, mean |N(v_s)| %.2f, %llu on a boundary\n", (unsigned long long)splits, valence,
              (unsigned long long)boundary);

  const protocol::StreamContext context = protocol::stream_context(protocol::make_base(model, "model", 16));
  const std::vector<SchemeBits> rows = table2_bits(model, context);
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_NEAR(rows[0].indices, 2 + valence + double(missing_sides) / double(splits), 1e-9)
      << "explicit 1-ring: v_s, v_t and N(v_s), the top index value standing for a missing cut vertex";
  const double fixed_indices[] = {6, 8, 6, 3, 3};  // the other schemes' fields are fixed
  for (size_t k = 1; k < rows.size(); ++k) EXPECT_DOUBLE_EQ(rows[k].indices, fixed_indices[k - 1]) << k;
  for (const SchemeBits& row : rows) {
    EXPECT_LT(row.bits_fitted, row.bits_32) << row.framework;
    if (row.indices == double(row.paper_bits) / 32) {
      EXPECT_DOUBLE_EQ(row.bits_32, row.paper_bits) << row.framework;
    }
    std::printf("%-22s %6.1f bits at 32-bit ids (paper %u), %6.1f at the model's widths\n", row.framework.c_str(),
                row.bits_32, row.paper_bits, row.bits_fitted);
  }
  EXPECT_LE(rows[5].bits_fitted, 96) << "a packet's <tree-id, node-id> ids fit the paper's three 32-bit words";
  EXPECT_LT(rows[4].bits_fitted, rows[1].bits_fitted) << "three ids against El-Sana et al.'s six";
}

TEST(TopologySchemes, ReplayMatchesTheEngineAndSchemesCountTheirFields) { PMS_MEASURE_RECORD_BITS_MODEL(check_replay); }

}  // namespace
}  // namespace pms::bench
