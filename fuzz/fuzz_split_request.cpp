// libFuzzer target for the receiver-driven request code (docs/architecture.md, "Correctness properties", 5):
// the first 4 bytes pick the decoder's limits (trees, deepest split, ids, depth), the rest is the code. Any
// bytes must decode or throw ProtocolError; what decodes must respect every limit, come in code order and
// re-encode to the same bytes (one encoding per id set, so one URL per request).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "protocol/message_types.h"
#include "protocol/split_request.h"
#include "spm/vertex_id.h"

namespace {

using namespace pms::protocol;

void check(bool condition) {
  if (!condition) __builtin_trap();
}

SplitRequestLimits limits_from(const uint8_t* b) {
  SplitRequestLimits limits;
  limits.root_count = 1 + (uint32_t(b[0]) | uint32_t(b[1] & 0x7F) << 8) * (b[1] & 0x80 ? 65537u : 1u);
  limits.max_node_depth = int(b[2] % 64) - 1;
  limits.max_ids = 1 + b[3] % 64 * 16;
  limits.max_depth = b[3] / 64 * 3;
  limits.max_bytes = 4096;
  return limits;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  const SplitRequestLimits limits = limits_from(data);
  const std::span<const uint8_t> code(data + 4, size - 4);
  SplitRequest request;
  try {
    request = decode_split_request(code, limits);
  } catch (const ProtocolError&) {
    return 0;
  }
  check(!request.ids.empty() && request.ids.size() <= limits.max_ids && request.depth <= limits.max_depth);
  for (size_t i = 0; i < request.ids.size(); ++i) {
    const pms::VertexId v = request.ids[i];
    check(v.tree < limits.root_count && v.depth() <= limits.max_node_depth);
    if (i > 0) check(code_order(request.ids[i - 1], v) && !pms::is_ancestor_or_self(request.ids[i - 1], v));
  }
  const std::vector<uint8_t> again = encode_split_request(request);
  check(again.size() == code.size() && std::equal(again.begin(), again.end(), code.begin()));
  return 0;
}
