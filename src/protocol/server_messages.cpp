// Server -> client messages other than BASE and VSPLITS: HELLO_OK, CATALOGUE, ERROR (docs/protocol.md).
#include "protocol/server_messages.h"
#include "protocol/message_types.h"
#include "protocol/wire_internal.h"

namespace pms::protocol {
namespace {

constexpr uint8_t kFlagNormals = 1, kFlagColors = 2;
// The smallest catalogue entry: empty name (u16) + u64 + u32 + u64 + 3 x u8.
constexpr uint64_t kMinModelInfoBits = 8 * (2 + 8 + 4 + 8 + 3);

}  // namespace

std::vector<uint8_t> encode(const HelloOk& m) {
  Writer w(MessageType::hello_ok);
  w.u16(m.version);
  w.string(m.server_name, kMaxNameBytes, "server name");
  w.u32(m.max_client_message);
  w.u32(m.max_server_message);
  return w.finish();
}

HelloOk decode_hello_ok(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::hello_ok);
  HelloOk m;
  m.version = r.u16("version");
  m.server_name = r.string(kMaxNameBytes, "server name");
  m.max_client_message = r.u32("max client message");
  m.max_server_message = r.u32("max server message");
  r.expect_end();
  return m;
}

std::vector<uint8_t> encode(const Catalogue& m) {
  Writer w(MessageType::catalogue);
  if (m.models.size() > UINT32_MAX) fail("CATALOGUE", "too many models");
  w.u32(uint32_t(m.models.size()));
  for (const ModelInfo& info : m.models) {
    if (info.tree_id_bits < 1 || info.tree_id_bits > 32 || info.node_id_bits > 63)
      fail("CATALOGUE", info.name + ": id widths outside 1..32 / 0..63");
    w.string(info.name, kMaxNameBytes, "model name");
    w.u64(info.input_faces);
    w.u32(info.base_vertices);
    w.u64(info.vsplits);
    w.u8(uint8_t(info.tree_id_bits));
    w.u8(uint8_t(info.node_id_bits));
    w.u8(uint8_t((info.has_normals ? kFlagNormals : 0) | (info.has_colors ? kFlagColors : 0)));
  }
  return w.finish();
}

Catalogue decode_catalogue(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::catalogue);
  const uint32_t count = r.u32("model count");
  r.check_count(count, kMinModelInfoBits, "model count");
  Catalogue m;
  m.models.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    r.set_item("model", i);
    ModelInfo& info = m.models[i];
    info.name = r.string(kMaxNameBytes, "name");
    info.input_faces = r.u64("input faces");
    info.base_vertices = r.u32("base vertices");
    info.vsplits = r.u64("vsplits");
    info.tree_id_bits = r.u8("tree_id_bits");
    if (info.tree_id_bits < 1 || info.tree_id_bits > 32) r.fail(ErrorCode::bad_message, "tree_id_bits", "not in 1..32");
    info.node_id_bits = r.u8("node_id_bits");
    if (info.node_id_bits > 63) r.fail(ErrorCode::bad_message, "node_id_bits", "over 63");
    const uint8_t flags = r.u8("flags");
    if (flags & ~(kFlagNormals | kFlagColors)) r.fail(ErrorCode::bad_message, "flags", "unknown bits set");
    info.has_normals = flags & kFlagNormals;
    info.has_colors = flags & kFlagColors;
  }
  r.clear_item();
  r.expect_end();
  return m;
}

std::vector<uint8_t> encode(const ErrorMessage& m) {
  Writer w(MessageType::error);
  w.u16(uint16_t(m.code));
  w.string(m.text, UINT16_MAX, "text");
  return w.finish();
}

ErrorMessage decode_error(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::error);
  ErrorMessage m;
  m.code = ErrorCode(r.u16("code"));  // a newer server's code is still an error: passed through
  m.text = r.string(UINT16_MAX, "text");
  r.expect_end();
  return m;
}

}  // namespace pms::protocol
