// kim-lee-kobbelt 2005 §7.2, Table 2: the topological detail a vsplit packet carries in each view-dependent
// streaming framework the table compares, measured on a model's own splits (bench E2). The paper counts
// fields at 32 bits each with an assumed valence of 6; here every split of the PM order is replayed on a
// mesh, so each scheme's fields (N(v_s), the min/max ids of N(v_s), f_l, f_r and the four faces beside them)
// are the ones that split really has, and each is written at 32 bits and at the model's own index widths.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "protocol/stream_context.h"
#include "spm/hierarchy.h"

namespace pms::bench {

// What the PM-order replay saw at one split (node indices; face indices in creation order, base faces
// first). kNone: a side the split does not have (a boundary edge).
struct SplitTopology {
  uint32_t vs = kNone, vt = kNone;
  uint32_t vl = kNone, vr = kNone;  // the cut vertices in the mesh M^i the split applies to
  std::vector<uint32_t> neighbours;  // N(v_s) in M^i, v_l and v_r first when present
  uint32_t min_id = kNone, max_id = kNone;  // over N(v_s) (El-Sana & Varshney 1999's implicit dependencies)
  uint32_t fl = kNone, fr = kNone;
  uint32_t fn[4] = {kNone, kNone, kNone, kNone};  // beside f_l across (u, l), (l, t); beside f_r across (t, r), (r, u)
};

// Replays `model`'s split order from its base mesh (docs/internals.md, "Half-edge collapse and vertex split")
// and hands each split's topology to `visit`. Returns the final mesh's faces as leaf node triples, CCW, in
// creation order. pms::Error when a split's cut vertices are not beside v_s (the model is inconsistent).
std::vector<uint32_t> replay_pm_topology(const ModelData& model,
                                         const std::function<void(const SplitTopology&)>& visit);

// One row of Table 2 on one model: mean bits per split with every index at 32 bits (the paper's convention;
// its column is `paper_bits`, which assumes 6 neighbours) and at the model's index widths (a vertex id in
// bit_width(nodes) bits, a face id in bit_width(faces) bits, the top value meaning "none"), and the mean
// number of indices per split.
struct SchemeBits {
  std::string framework, scheme, fields;
  uint32_t paper_bits = 0;
  double indices = 0, bits_32 = 0, bits_fitted = 0;
};

// Every scheme of Table 2 over every split of `model`, ours last, then ours as a pmstream packet codes its
// topology (`context`'s <tree-id, node-id> ids and the cut flags, protocol::packet_bits).
std::vector<SchemeBits> table2_bits(const ModelData& model, const protocol::StreamContext& context);

}  // namespace pms::bench
