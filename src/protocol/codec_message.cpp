// CODEC (docs/protocol.md): a model's split record tables, once per session after BASE when the session's
// VSPLITS packets are split records (carries_split_records). The payload is SplitCodec::serialize's bytes,
// the same as GET /models/{m}/codec, so the one serialization has one decoder and its checks.
#include <memory>
#include <string>

#include "common/bit_stream.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "spm/split_codec.h"

namespace pms::protocol {

std::vector<uint8_t> encode(const Codec& m) {
  Writer w(MessageType::codec);
  w.reserve_payload(m.tables.size());
  for (uint8_t b : m.tables) w.u8(b);
  return w.finish();
}

Codec decode_codec(std::span<const uint8_t> payload, const StreamContext& c) {
  Reader r(payload, MessageType::codec);
  if (const std::string why = check_context(c); !why.empty()) r.fail(ErrorCode::internal, "stream context", why);
  BitReader bits(payload, "tables");
  Codec m;
  try {
    m.codec = std::make_shared<const SplitCodec>(SplitCodec::deserialize(bits));
  } catch (const Error& e) {
    r.fail(ErrorCode::bad_message, "tables", e.what());
  }
  r.seek(bits.position());
  r.expect_end();  // zero padding to the byte, nothing after: one encoding
  if (m.codec->root_count() != c.root_count || m.codec->max_depth() != c.node_id_bits ||
      m.codec->position_bits() != c.grid.bits)
    r.fail(ErrorCode::bad_message, "tables",
           "for " + std::to_string(m.codec->root_count()) + " roots, depth " + std::to_string(m.codec->max_depth()) +
               " and " + std::to_string(m.codec->position_bits()) + " position bits; BASE says " +
               std::to_string(c.root_count) + ", " + std::to_string(c.node_id_bits) + " and " +
               std::to_string(c.grid.bits));
  if (m.codec->has_normals() != c.has_normals || m.codec->has_colors() != c.has_colors)
    r.fail(ErrorCode::bad_message, "tables", "the records would carry other attributes than BASE's normals and colors");
  m.tables.assign(payload.begin(), payload.end());
  return m;
}

}  // namespace pms::protocol
