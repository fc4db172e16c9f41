// What a server sends (docs/protocol.md): HELLO_OK, CATALOGUE, BASE, VSPLITS, DAG_OPS, ERROR, and their codecs.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "protocol/message_types.h"
#include "protocol/stream_context.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_codec.h"
#include "spm/split_record.h"

namespace pms::protocol {

struct HelloOk {
  uint16_t version = kProtocolVersion;
  std::string server_name;
  uint32_t max_client_message = kDefaultMaxMessage;  // largest payload the server accepts
  uint32_t max_server_message = kDefaultMaxMessage;  // largest payload the server sends
};

struct ModelInfo {
  std::string name;
  uint64_t input_faces = 0;
  uint32_t base_vertices = 0;
  uint64_t vsplits = 0;
  uint32_t tree_id_bits = 1;
  uint32_t node_id_bits = 0;
  bool has_normals = false;
  bool has_colors = false;
};
struct Catalogue {
  std::vector<ModelInfo> models;
};

// The base mesh with everything the client needs to refine it: roots (tree-id = index) with positions,
// refinement info and attributes, faces as root triples. Positions are the exact ones when encoding (they
// are quantized on the wire) and the dequantized ones after decoding.
struct Base {
  std::string model;
  float bbox_min[3] = {0, 0, 0};
  float bbox_max[3] = {0, 0, 0};
  float scale = 1;  // refinement info is relative to it (spm/refine_info.h)
  uint32_t tree_id_bits = 1;
  uint32_t node_id_bits = 0;
  uint32_t position_bits = kDefaultPositionBits;
  bool has_normals = false;
  bool has_colors = false;
  std::vector<float> positions;  // 3 per root
  std::vector<RefineInfo> refine;
  std::vector<float> normals;   // 3 per root when has_normals (octahedral 2 x 16 bits on the wire)
  std::vector<uint8_t> colors;  // 4 per root when has_colors
  std::vector<uint32_t> faces;  // 3 root indices per face, CCW
  uint32_t root_count() const { return uint32_t(refine.size()); }
};

// A model's split record tables (SplitCodec::serialize, padded to a byte; the bytes of GET
// /models/{m}/codec), once after BASE in a session whose packets are split records (carries_split_records).
struct Codec {
  std::vector<uint8_t> tables;
  std::shared_ptr<const SplitCodec> codec;  // what decode_codec read from `tables`; the encoder ignores it
};

// One VIEW's answer may take several batches; the last has `final` set.
struct VSplits {
  uint32_t frame = 0;
  bool final = false;
  std::vector<SplitRecord> splits;  // in the order the client must apply them (parents and partial order first)
  // Sent ahead (an AHEAD's, docs/protocol.md): held by the client until a view wants it; answers no VIEW,
  // so never final, and `frame` is the AHEAD's.
  bool ahead = false;
};

// DAG_OPS (StreamMode::dag): one DAG_VIEW's operations in the order the client applies them, collapses
// (v_s ids: v_t and v_u merge back) before splits (packets as in VSPLITS, without refinement info);
// an answer may take several messages, the last has `final` set.
struct DagOps {
  uint32_t frame = 0;
  bool final = false;
  std::vector<VertexId> collapses;
  std::vector<SplitRecord> splits;
};

struct ErrorMessage {
  ErrorCode code = ErrorCode::internal;
  std::string text;
};

// ---- encoders: each returns a whole frame (header + payload) -------------------------------------------
// They throw pms::Error for values the format cannot carry (a name over kMaxNameBytes, an id beyond the
// context's widths, a resume list that is not a front).
std::vector<uint8_t> encode(const HelloOk& m);
std::vector<uint8_t> encode(const Catalogue& m);
std::vector<uint8_t> encode(const Base& m);
std::vector<uint8_t> encode(const Codec& m);
// With context.records, each packet is v_s's id and its split record coded against context.held (or the
// batch's own earlier splits); pms::Error for a v_s neither holds.
std::vector<uint8_t> encode(const VSplits& m, const StreamContext& context);
std::vector<uint8_t> encode(const ErrorMessage& m);
std::vector<uint8_t> encode(const DagOps& m, const StreamContext& context);

// ---- decoders: payload (without the frame header) -> message; throw ProtocolError ----------------------
HelloOk decode_hello_ok(std::span<const uint8_t> payload);
Catalogue decode_catalogue(std::span<const uint8_t> payload);
Base decode_base(std::span<const uint8_t> payload);
// The tables must fit the model of `context` (root count, max depth, position bits).
Codec decode_codec(std::span<const uint8_t> payload, const StreamContext& context);
// With context.records: bad_id for a v_s that context.held and the batch's earlier splits do not hold, or
// one split twice in the batch; bad_message for a record SplitCodec::decode refuses.
VSplits decode_vsplits(std::span<const uint8_t> payload, const StreamContext& context);
ErrorMessage decode_error(std::span<const uint8_t> payload);
DagOps decode_dag_ops(std::span<const uint8_t> payload,
                      const StreamContext& context);  // codes this build does not know pass through

// What a receiver decodes for `info` (spm/refine_info.h): every mode, split records included, delivers it.
using pms::as_sent;

}  // namespace pms::protocol
