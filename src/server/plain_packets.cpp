// kim-lee-kobbelt §6.3: the fundamental cut vertices of each packet replaced by the client's actual ones.
#include "server/plain_packets.h"

#include "common/error.h"
#include "protocol/server_messages.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::server {
namespace {

// A side the fundamental split has must have an actual vertex, and only such a side.
VertexId actual_id(const ModelData& model, VertexId fundamental, uint32_t actual) {
  if (is_vertex(fundamental) != (actual != kNone) || (actual != kNone && actual >= model.node_count()))
    fail("VSPLITS", "actual cut vertices that do not match the split's sides");
  return actual == kNone ? kNoVertex : model.id(actual);
}

}  // namespace

std::vector<uint8_t> encode_plain_batch(const ModelData& model, const protocol::StreamContext& wire, uint32_t frame,
                                        bool final, std::span<const uint32_t> nodes, std::span<const ActualCuts> cuts) {
  if (nodes.size() != cuts.size()) fail("VSPLITS", "one set of actual cut vertices per split is needed");
  if (wire.has_refinement) fail("VSPLITS", "plain packets carry no refinement info");
  protocol::VSplits message;
  message.frame = frame;
  message.final = final;
  message.splits.reserve(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    SplitRecord split = split_record(model, nodes[i]);
    split.cut_l = actual_id(model, split.cut_l, cuts[i].left);
    split.cut_r = actual_id(model, split.cut_r, cuts[i].right);
    message.splits.push_back(split);
  }
  return protocol::encode(message, wire);
}

}  // namespace pms::server
