#include "protocol/split_bands.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "spm/octahedral_normal.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"

namespace pms::protocol {
namespace {

struct BandEntry {
  uint32_t node;   // a model node (writer) or a hierarchy slot (reader)
  uint32_t level;  // below the band's root
};

void copy_record(const StoredRecords& records, uint32_t node, BitWriter& w) {
  w.append(records.bits, records.offsets[node], records.offsets[node + 1]);
}

// A child whose info can refine has a split of its own (every leaf's info never refines); for one whose
// info never refines, the stream says, but in the plain form, whose records say it themselves.
bool child_has_split(const RefineInfo& info, RecordForm form, BitReader& r) {
  return !never_refines(info) || (form == RecordForm::info && r.bit("child's split"));
}

// The bit that says whether `child` has a split, where its info (in the info form) does not say it.
void write_presence(const ModelData& model, uint32_t child, bool split, BitWriter& w) {
  if (never_refines(as_sent(model.refine[child]))) w.bit(split ? 1 : 0);
  else if (!split) fail("split band", "leaf " + std::to_string(child) + " has an info that refines");
}

}  // namespace

uint32_t write_split_band(const ModelData& model, const StoredRecords& records, uint32_t root, uint32_t depth,
                          BitWriter& w) {
  if (model.is_leaf(root)) fail("split band", "node " + std::to_string(root) + " is a leaf");
  if (depth == 0) {  // most requests: no queue to allocate
    copy_record(records, root, w);
    return 1;
  }
  std::vector<BandEntry> queue{{root, 0}};
  for (size_t next = 0; next < queue.size(); ++next) {
    const auto [node, level] = queue[next];
    copy_record(records, node, w);
    if (level == depth) continue;
    for (uint32_t child = model.first_child[node]; child < model.first_child[node] + 2; ++child) {
      const bool split = !model.is_leaf(child);
      if (records.form == RecordForm::info) write_presence(model, child, split, w);
      if (split) queue.push_back({child, level + 1});
    }
  }
  return uint32_t(queue.size());
}

SplitRecord split_record_of(VertexId vs, const SplitPayload& payload, const PositionGrid& grid,
                            const SplitCodec& codec) {
  SplitRecord split;
  split.vs = vs;
  split.cut_l = payload.cut_l;
  split.cut_r = payload.cut_r;
  dequantize_position(grid, payload.position_t, split.position_t);
  split.info_t = payload.info_t;
  split.info_u = payload.info_u;
  split.has_normal = codec.has_normals();
  if (split.has_normal) decode_normal(payload.normal_t, split.normal_t);
  split.has_color = codec.has_colors();
  if (split.has_color) std::copy_n(payload.color_t, 4, split.color_t);
  return split;
}

SplitContext held_split_context(const VertexHierarchy& h, uint32_t slot, const PositionGrid& grid) {
  SplitContext c;
  c.vs = h.id(slot);
  quantize_position(grid, h.position(slot), c.position_s);
  c.info_s = h.refine(slot);
  // A normal decoded from the wire encodes back to the integers sent (spm/octahedral_normal.h).
  if (h.has_normals()) encode_normal(h.normal(slot), c.normal_s);
  if (h.has_colors()) std::copy_n(h.color(slot), 4, c.color_s);
  uint32_t s = slot;
  for (int i = 0; i < kCutAncestors; ++i) {
    s = h.parent(s);
    if (s == kNone) break;
    c.ancestor_cuts[2 * size_t(i)] = h.cut_left(s);
    c.ancestor_cuts[2 * size_t(i) + 1] = h.cut_right(s);
  }
  return c;
}

std::function<bool(VertexId, SplitContext&)> held_in(const VertexHierarchy& h, const PositionGrid& grid) {
  return [&h, grid](VertexId id, SplitContext& out) {
    const uint32_t slot = h.find(id);
    if (slot == kNone) return false;
    out = held_split_context(h, slot, grid);
    return true;
  };
}

uint32_t read_split_bands(std::span<const uint8_t> body, const SplitRequest& request, const SplitCodec& codec,
                          const PositionGrid& grid, VertexHierarchy& h, uint32_t max_splits) {
  BitReader r(body, "split records");
  uint32_t records = 0, added = 0;
  std::vector<BandEntry> queue;
  for (VertexId id : request.ids) {
    const uint32_t root = h.find(id);
    if (root == kNone) fail("split records", "an answer for " + to_string(id) + ", which this client does not hold");
    queue.assign(1, {root, 0});
    for (size_t next = 0; next < queue.size(); ++next) {
      const auto [slot, level] = queue[next];
      if (++records > max_splits) fail("split records", "more than " + std::to_string(max_splits) + " records");
      const SplitPayload p = codec.decode(held_split_context(h, slot, grid), r);
      if (h.is_leaf(slot)) {
        h.add_split(split_record_of(h.id(slot), p, grid, codec));
        ++added;
      }
      if (level == request.depth) continue;
      const RefineInfo* infos[2] = {&p.info_t, &p.info_u};
      for (uint32_t k = 0; k < 2; ++k)
        if (child_has_split(*infos[k], codec.form(), r)) queue.push_back({h.first_child(slot) + k, level + 1});
    }
  }
  // The writer pads the stream to a byte with zeros.
  if (r.bits_left() >= 8 || (r.bits_left() && r.bits(unsigned(r.bits_left()), "padding") != 0))
    fail("split records", "bits after the last record");
  return added;
}

}  // namespace pms::protocol
