// libFuzzer target for every protocol message decoder (docs/architecture.md, "Correctness properties", 5): the
// first byte picks the decoder, VSPLITS and DAG_OPS take its stream context from the next 8 bytes, the rest is the
// payload (AHEAD: 14). VSPLITS with split records (which = 12) and CODEC (13) take u16 T | T bytes of code tables first
// (hostile tables too) and a context made to fit them, whose client holds the roots. Any bytes must decode or throw
// ProtocolError — never crash, hang, over-allocate or throw anything else — and what decodes must re-encode and decode
// to the same message (byte for byte where no quantization is involved).
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <vector>

#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "spm/split_codec.h"
#include "spm/split_record.h"

namespace {

using namespace pms::protocol;

std::span<const uint8_t> payload_of(const std::vector<uint8_t>& frame) {
  return std::span<const uint8_t>(frame).subspan(kFrameHeaderBytes);
}

bool same(std::span<const uint8_t> a, std::span<const uint8_t> b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size()) == 0);
}

void check(bool condition) {
  if (!condition) __builtin_trap();
}

// A context from 8 bytes, always one the encoder accepts: widths clamped into their valid ranges.
StreamContext context_from(const uint8_t* b) {
  StreamContext c;
  c.tree_id_bits = 1 + b[0] % 32;
  const uint64_t max_roots = uint64_t(1) << c.tree_id_bits;
  c.root_count = uint32_t(1 + (uint64_t(b[1]) | uint64_t(b[2]) << 8 | uint64_t(b[3]) << 16) % max_roots);
  c.node_id_bits = b[4] % 64;
  static const uint32_t kBits[] = {1, 5, 8, 12, 16, 20, 24, 32};
  c.grid.bits = kBits[b[5] % 8];
  c.has_normals = b[6] & 1;
  c.has_colors = b[6] & 2;
  c.has_refinement = !(b[6] & 4);  // a view-independent session's packets
  for (int i = 0; i < 3; ++i) {
    c.grid.min[i] = -1.0f - float(b[7] % 4);
    c.grid.max[i] = 1.0f + float(b[7] / 4 % 4);
  }
  return c;
}

bool same_split(const pms::SplitRecord& a, const pms::SplitRecord& b) {
  return a.vs == b.vs && a.cut_l == b.cut_l && a.cut_r == b.cut_r && a.info_t == b.info_t && a.info_u == b.info_u &&
         a.has_normal == b.has_normal && a.has_color == b.has_color && std::memcmp(a.color_t, b.color_t, 4) == 0;
}

// A sender-driven context for the tables at the front of `payload` (the rest is the message), or false.
bool records_context(std::span<const uint8_t>& payload, StreamContext& c, std::vector<uint8_t>& tables) {
  if (payload.size() < 2) return false;
  const size_t size = size_t(payload[0]) | size_t(payload[1]) << 8;
  if (size > payload.size() - 2) return false;
  tables.assign(payload.begin() + 2, payload.begin() + 2 + ptrdiff_t(size));
  payload = payload.subspan(2 + size);
  try {
    pms::BitReader r(tables, "tables");
    c.records = std::make_shared<const pms::SplitCodec>(pms::SplitCodec::deserialize(r));
  } catch (const pms::Error&) {
    return false;
  }
  c.root_count = c.records->root_count();
  c.tree_id_bits = std::max<uint32_t>(1, uint32_t(std::bit_width(c.root_count - 1)));
  c.node_id_bits = c.records->max_depth();
  c.grid.bits = c.records->position_bits();
  if (!pms::valid_position_bits(c.grid.bits)) return false;
  c.has_normals = c.has_colors = false;
  c.has_refinement = true;
  // The client holds the roots, at positions and with an info spread over the grid and the codes.
  c.held = [bits = c.grid.bits](pms::VertexId id, pms::SplitContext& out) {
    if (!id.is_root()) return false;
    out = {};
    out.vs = id;
    const uint32_t top = bits >= 32 ? 0x3F800000u : (1u << bits) - 1;  // raw floats: 1.0f
    for (int i = 0; i < 3; ++i) out.position_s[i] = bits >= 32 ? top : (id.tree * 2654435761u >> i) & top;
    if (id.tree % 3) out.info_s = {0x2C00, 0x2400, 0x2000, 12, uint16_t(int16_t(-40)), 300};
    return true;
  };
  return true;
}

void fuzz_one(uint8_t which, std::span<const uint8_t> payload, const StreamContext& given) {
  StreamContext context = given;
  std::vector<uint8_t> tables;
  if (which % 15 >= 12 && which % 15 <= 13 && !records_context(payload, context, tables)) return;
  switch (which % 15) {
    case 0:
      check(same(payload_of(encode(decode_hello(payload))), payload));
      break;
    case 1:
      check(same(payload_of(encode(decode_list(payload))), payload));
      break;
    case 2:
      check(same(payload_of(encode(decode_open(payload, 1u << 16))), payload));
      break;
    case 3:
      check(same(payload_of(encode(decode_view(payload))), payload));
      break;
    case 4:
      check(same(payload_of(encode(decode_close(payload))), payload));
      break;
    case 5:
      check(same(payload_of(encode(decode_hello_ok(payload))), payload));
      break;
    case 6:
      check(same(payload_of(encode(decode_catalogue(payload))), payload));
      break;
    case 7: {
      // Positions and normals may move by a rounding step when re-quantized; the rest must not change.
      const Base base = decode_base(payload);
      const std::vector<uint8_t> again = encode(base);
      const Base back = decode_base(payload_of(again));
      check(back.refine == base.refine && back.faces == base.faces && back.colors == base.colors &&
            back.positions.size() == base.positions.size() && back.normals.size() == base.normals.size());
      break;
    }
    case 8: {
      const VSplits batch = decode_vsplits(payload, context);
      const VSplits back = decode_vsplits(payload_of(encode(batch, context)), context);
      check(back.frame == batch.frame && back.final == batch.final && back.ahead == batch.ahead &&
            back.splits.size() == batch.splits.size());
      for (size_t i = 0; i < batch.splits.size(); ++i) check(same_split(back.splits[i], batch.splits[i]));
      break;
    }
    case 9:
      check(same(payload_of(encode(decode_error(payload))), payload));
      break;
    case 10:
      check(same(payload_of(encode(decode_dag_view(payload))), payload));
      break;
    case 12: {
      const VSplits batch = decode_vsplits(payload, context);
      std::vector<uint8_t> again;
      try {
        again = encode(batch, context);
      } catch (const ProtocolError&) {
        __builtin_trap();
      } catch (const pms::Error&) {
        break;  // hostile tables may lack the code words the encoder's own choice needs
      }
      const VSplits back = decode_vsplits(payload_of(again), context);
      check(back.frame == batch.frame && back.final == batch.final && back.ahead == batch.ahead &&
            back.splits.size() == batch.splits.size());
      for (size_t i = 0; i < batch.splits.size(); ++i) check(same_split(back.splits[i], batch.splits[i]));
      break;
    }
    case 14:
      check(same(payload_of(encode(decode_ahead(payload))), payload));
      break;
    case 13: {
      const Codec codec = decode_codec(payload, context);
      check(same(payload_of(encode(codec)), payload));
      break;
    }
    case 11: {
      const DagOps ops = decode_dag_ops(payload, context);
      const DagOps back = decode_dag_ops(payload_of(encode(ops, context)), context);
      check(back.frame == ops.frame && back.final == ops.final && back.collapses == ops.collapses &&
            back.splits.size() == ops.splits.size());
      for (size_t i = 0; i < ops.splits.size(); ++i) check(same_split(back.splits[i], ops.splits[i]));
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 9) return 0;
  const StreamContext context = context_from(data + 1);
  try {
    fuzz_one(data[0], std::span<const uint8_t>(data + 9, size - 9), context);
  } catch (const ProtocolError&) {
  }
  return 0;
}
