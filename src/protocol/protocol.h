// Wire messages of the sender-driven protocol (kim-lee-kobbelt 2005 §5, Fig. 3; DESIGN.md §4) as pure
// codecs: bytes in, structs out and back. No sockets here; the server and client layers do the I/O.
// Byte layouts, limits and error codes: docs/protocol.md.
//
// Framing: every message is  u32 LE payload length | u8 MessageType | payload.
// Decoders check lengths, counts and ids against limits before allocating and throw ProtocolError
// ("VSPLITS: packet 12: v_l tree-id: 70 >= root count 62"); the code says which ERROR to answer with.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "common/error.h"
#include "pm/pm.h"
#include "refine/camera.h"
#include "refine/refine.h"

namespace pms::protocol {

// 3: a node with mu = delta = 0 sends its refinement info as one flag bit (2 sent 43 or 65 bits for
// every node, 1 sent 6 x u16).
constexpr uint16_t kProtocolVersion = 3;
constexpr char kMagic[4] = {'P', 'M', 'S', 'T'};
constexpr size_t kFrameHeaderBytes = 5;                 // u32 payload length + u8 type
constexpr uint32_t kDefaultMaxMessage = 16u << 20;      // payload bytes a reader accepts by default
constexpr size_t kMaxNameBytes = 1024;                  // model, client and server names
constexpr uint64_t kDefaultMaxResumeLeaves = 1u << 22;  // OPEN: leaves a resume front may list
constexpr uint32_t kDefaultPositionBits = 16;

// Client -> server types have the high bit clear, server -> client set.
enum class MessageType : uint8_t {
  hello = 0x01,
  list = 0x02,
  open = 0x03,
  view = 0x04,
  close = 0x05,
  hello_ok = 0x81,
  catalogue = 0x82,
  base = 0x83,
  vsplits = 0x84,
  error = 0x85,
};
std::string to_string(MessageType type);  // "VSPLITS", or "type 0x42" for an unknown byte

enum class ErrorCode : uint16_t {
  bad_message = 1,          // malformed framing or payload
  unsupported_version = 2,  // HELLO with a version the server does not speak
  unknown_model = 3,        // OPEN of a name not in the catalogue
  bad_id = 4,               // a vertex id outside the model (tree, depth or node)
  too_large = 5,            // a frame over the receiver's limit
  out_of_order = 6,         // a message the session's state does not allow yet (VIEW before OPEN)
  server_full = 7,
  timeout = 8,
  internal = 9,
};
std::string to_string(ErrorCode code);  // "bad_message", or "code 42" for a value this build does not know

// What every decoder and the frame reader throw; `code` is the ERROR to answer with.
struct ProtocolError : Error {
  ErrorCode code;
  ProtocolError(ErrorCode c, const std::string& what) : Error(what), code(c) {}
};

// ---- framing -------------------------------------------------------------------------------------------

struct Frame {
  MessageType type{};  // may hold a byte no enumerator names: the message decoders reject it
  std::vector<uint8_t> payload;
};

// Incremental decoder for a byte stream cut into arbitrary chunks. A header announcing more than
// `max_payload` bytes is refused as soon as its 5 bytes are in, before anything is allocated for it;
// payload buffers grow with the bytes that actually arrive, so a peer that announces 16 MiB and sends
// 10 bytes costs 10 bytes. Errors surface in stream order: next() first hands out the frames that came
// before the bad header, then throws ProtocolError(too_large), and keeps throwing (a stream cannot be
// resynchronized; later bytes are ignored). How the bytes were chunked never changes the outcome.
class FrameReader {
 public:
  explicit FrameReader(uint32_t max_payload = kDefaultMaxMessage);

  void feed(const uint8_t* data, size_t size);
  void feed(std::span<const uint8_t> bytes) { feed(bytes.data(), bytes.size()); }
  bool next(Frame& frame);  // pops the oldest complete frame; false if none; throws once failed and drained
  size_t ready() const { return ready_.size(); }
  bool failed() const { return !failed_.empty(); }
  // Bytes of an unfinished frame are buffered: a stream that ends now was cut mid-message.
  bool mid_frame() const { return header_fill_ > 0; }
  uint32_t max_payload() const { return max_payload_; }

 private:
  uint32_t max_payload_;
  uint8_t header_[kFrameHeaderBytes] = {};
  size_t header_fill_ = 0;
  uint32_t payload_size_ = 0;
  Frame current_;
  std::deque<Frame> ready_;
  std::string failed_;  // sticky error text
};

// ---- quantized geometry --------------------------------------------------------------------------------

// Positions on the wire: `bits` per axis on a uniform grid over the model's bounding box (1..24 bits),
// or the raw float32 bits (32). Client and server must evaluate refinement criteria on the same numbers,
// so the server quantizes the model's exact positions when it encodes and evaluates qrefine on
// dequantize(quantize(p)) (snap_position); the client only ever sees the dequantized values.
struct PositionGrid {
  float min[3] = {0, 0, 0};
  float max[3] = {0, 0, 0};
  uint32_t bits = kDefaultPositionBits;
};
bool valid_position_bits(uint32_t bits);  // 1..24 or 32
// Clamps to the box; non-finite coordinates become the box minimum (grid) or stay as they are (32 bits).
void quantize_position(const PositionGrid& grid, const float p[3], uint32_t q[3]);
void dequantize_position(const PositionGrid& grid, const uint32_t q[3], float p[3]);
void snap_position(const PositionGrid& grid, const float p[3], float out[3]);  // dequantize(quantize(p))
// Largest |dequantize(quantize(p)) - p| per axis for p inside the box (half a grid step, plus float rounding).
float position_error_bound(const PositionGrid& grid, int axis);

// ---- the session context both ends derive from BASE ----------------------------------------------------

// What a vsplit packet's decoder needs to know about the model: id widths, the position grid and which
// attributes travel. The server builds it from the BASE it sends, the client from the BASE it receives.
struct StreamContext {
  uint32_t root_count = 1;    // tree-ids are < root_count
  uint32_t tree_id_bits = 1;  // 1..32, enough for root_count - 1
  uint32_t node_id_bits = 0;  // the hierarchy's max depth (<= 63)
  PositionGrid grid;
  bool has_normals = false;
  bool has_colors = false;
  // Packets carry info_t and info_u. Not in a view-independent session (kim-lee-kobbelt §8, Fig. 9): its
  // client applies splits in PM order and never evaluates qrefine. Both ends set it from the OPEN's mode.
  bool has_refinement = true;
};

// ---- client -> server ----------------------------------------------------------------------------------

struct Hello {
  uint16_t version = kProtocolVersion;
  std::string client_name;
};
struct List {};
// `resume`: the leaves of the partial hierarchy the client already holds (everything it received in an
// earlier session: DESIGN.md §9), so the server's active tags can be rebuilt and no vsplit is sent twice.
// Empty = a fresh session. A non-empty list must be a complete front of trees 0..R-1 (every root-to-leaf
// path meets exactly one listed id): the client's known leaves always are. It travels as a preorder
// split/leaf bit code (about 2 bits per leaf, not ~40).
// `mode`: sender-driven (kim-lee-kobbelt §5.3, the default) or view-independent, the baseline of §8 Fig. 9:
// the server streams the plain PM order (coarse to fine, packets without refinement info) until the prefix
// sent satisfies the client's view, and the client applies every split as it arrives.
enum class StreamMode : uint8_t { sender_driven, view_independent };
struct Open {
  std::string model;
  std::vector<VertexId> resume;
  StreamMode mode = StreamMode::sender_driven;
};
// The Camera itself rather than a modelview matrix: client and server both call make_view() on it with
// the model's box and get bit-identical ViewParams, so qrefine agrees on both sides.
struct View {
  Camera camera;
  float tolerance = 1;  // tau, screen-space error in pixels
  uint32_t frame = 0;   // echoed in the VSPLITS that answer it
};
struct Close {};

// OPEN up to its resume front. A front may list millions of leaves; a server decodes it with FrontDecoder a
// slice at a time instead of all at once inside one message handler.
struct OpenHeader {
  std::string model;
  StreamMode mode = StreamMode::sender_driven;
  bool resume = false;
  uint32_t resume_trees = 0;  // trees 0..resume_trees-1 are covered
  uint64_t front_bit = 0;     // where the front's code starts in the payload
};

// The preorder split/leaf code of a resume front, decoded incrementally: each next() call reads at most
// `max_leaves` leaves (and the split bits above them, at most 63 per leaf), so its work is bounded. The
// payload must outlive the decoder.
class FrontDecoder {
 public:
  FrontDecoder(std::span<const uint8_t> payload, const OpenHeader& header,
               uint64_t max_leaves = kDefaultMaxResumeLeaves);
  // Appends the next leaves, in preorder tree by tree; true once the front is complete and the payload
  // ends with it. Throws ProtocolError (bad_message, bad_id for a split below depth 63, too_large).
  bool next(size_t max_leaves, std::vector<VertexId>& out);
  uint64_t leaves() const { return leaves_; }
  bool done() const { return done_; }

 private:
  std::span<const uint8_t> payload_;
  uint64_t bit_;
  uint32_t trees_, tree_ = 0;
  uint64_t max_leaves_, leaves_ = 0;
  std::vector<VertexId> stack_;  // nodes whose bit is still to read, the next on top (at most 64)
  bool done_ = false;
};

// ---- server -> client ----------------------------------------------------------------------------------

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
  float scale = 1;  // refinement info is relative to it (pm.h)
  uint32_t tree_id_bits = 1;
  uint32_t node_id_bits = 0;
  uint32_t position_bits = kDefaultPositionBits;
  bool has_normals = false;
  bool has_colors = false;
  std::vector<float> positions;  // 3 per root
  std::vector<RefineInfo> refine;
  std::vector<float> normals;    // 3 per root when has_normals (octahedral 2 x 16 bits on the wire)
  std::vector<uint8_t> colors;   // 4 per root when has_colors
  std::vector<uint32_t> faces;   // 3 root indices per face, CCW
  uint32_t root_count() const { return uint32_t(refine.size()); }
};

// One VIEW's answer may take several batches; the last has `final` set.
struct VSplits {
  uint32_t frame = 0;
  bool final = false;
  std::vector<SplitRecord> splits;  // in the order the client must apply them (parents and partial order first)
};

struct ErrorMessage {
  ErrorCode code = ErrorCode::internal;
  std::string text;
};

// ---- encoders: each returns a whole frame (header + payload) -------------------------------------------
// They throw pms::Error for values the format cannot carry (a name over kMaxNameBytes, an id beyond the
// context's widths, a resume list that is not a front).

std::vector<uint8_t> encode(const Hello& m);
std::vector<uint8_t> encode(const List& m);
std::vector<uint8_t> encode(const Open& m);
std::vector<uint8_t> encode(const View& m);
std::vector<uint8_t> encode(const Close& m);
std::vector<uint8_t> encode(const HelloOk& m);
std::vector<uint8_t> encode(const Catalogue& m);
std::vector<uint8_t> encode(const Base& m);
std::vector<uint8_t> encode(const VSplits& m, const StreamContext& context);
std::vector<uint8_t> encode(const ErrorMessage& m);

// ---- decoders: payload (without the frame header) -> message; throw ProtocolError ----------------------

Hello decode_hello(std::span<const uint8_t> payload);  // checks the magic; the version is the server's call
List decode_list(std::span<const uint8_t> payload);
Open decode_open(std::span<const uint8_t> payload, uint64_t max_resume_leaves = kDefaultMaxResumeLeaves);
OpenHeader decode_open_header(std::span<const uint8_t> payload);  // the front is left to a FrontDecoder
View decode_view(std::span<const uint8_t> payload);  // also rejects cameras make_view() would refuse
Close decode_close(std::span<const uint8_t> payload);
HelloOk decode_hello_ok(std::span<const uint8_t> payload);
Catalogue decode_catalogue(std::span<const uint8_t> payload);
Base decode_base(std::span<const uint8_t> payload);
VSplits decode_vsplits(std::span<const uint8_t> payload, const StreamContext& context);
ErrorMessage decode_error(std::span<const uint8_t> payload);  // codes this build does not know pass through

using ClientMessage = std::variant<Hello, List, Open, View, Close>;
using ServerMessage = std::variant<HelloOk, Catalogue, Base, VSplits, ErrorMessage>;
// Dispatch on the frame's type; a server type (or unknown byte) from a client is bad_message and vice
// versa. VSPLITS needs the context of the BASE before it: without one (nullptr) it is out_of_order.
ClientMessage decode_client_message(const Frame& frame, uint64_t max_resume_leaves = kDefaultMaxResumeLeaves);
ServerMessage decode_server_message(const Frame& frame, const StreamContext* context);

// ---- building messages from a model --------------------------------------------------------------------

StreamContext stream_context(const Base& base);  // throws pms::Error for widths a decoder would reject
Base make_base(const ModelView& model, const std::string& name, uint32_t position_bits = kDefaultPositionBits);
ModelInfo model_info(const ModelView& model, const std::string& name);  // counts from the hierarchy itself

// ---- a server's packets, encoded once ------------------------------------------------------------------

// Every vsplit packet of a model as a sender-driven session sends it, encoded once and shared by all
// sessions: a VSPLITS batch is then its packets' bits copied back to back, with none of the per-packet
// reads of ids, positions and refinement info scattered over the model (the cache misses that dominated a
// server answering hundreds of first views). ~25 bytes per internal node and 8 per node on the real models.
class PacketTable {
 public:
  PacketTable() = default;
  // Throws pms::Error for a model the context cannot carry (as encode(VSplits) would).
  PacketTable(const ModelView& model, const StreamContext& context);
  bool empty() const { return where_.empty(); }
  size_t memory_bytes() const { return (bits_.capacity() + where_.capacity()) * sizeof(uint64_t); }

  // The same frame encode(VSplits{frame, final, splits of `nodes`}, context) gives; pms::Error for a node
  // that is not an internal node of the table's model.
  std::vector<uint8_t> encode(uint32_t frame, bool final, std::span<const uint32_t> nodes) const;

 private:
  static constexpr unsigned kLengthBits = 10;  // a packet is < 1024 bits (3 ids of <= 101 bits, info, attributes)
  std::vector<uint64_t> bits_;   // the packets back to back
  std::vector<uint64_t> where_;  // per node: bit offset << kLengthBits | bit count; 0 for a leaf
};

// ---- refinement info on the wire ------------------------------------------------------------------------

// What a receiver decodes for `info`. A node with mu = delta = 0 (every real leaf, about half of any
// hierarchy, and flat interior nodes) never asks to be refined whatever its radius and cone (criteria.h
// screen_error_exceeds), so its info travels as one flag bit and decodes with radius 0 and no cone; any
// other info arrives exactly as stored.
RefineInfo as_sent(const RefineInfo& info);

// ---- packet size accounting (kim-lee-kobbelt Table 2; bench E2) ----------------------------------------

// Bits one vsplit packet takes inside a VSPLITS bit stream. topology = the ids of v_s, v̂_l, v̂_r and the
// 2-bit cut flags (children are implied); position = v_t's quantized position; refinement = info_t +
// info_u (0 when the context has no refinement info); attributes = normal and color.
struct PacketBits {
  uint32_t topology = 0, position = 0, refinement = 0, attributes = 0;
  uint32_t total() const { return topology + position + refinement + attributes; }
};
PacketBits packet_bits(const SplitRecord& split, const StreamContext& context);
// Bits of one id: tree-id, depth field and the depth path bits below the root.
uint32_t id_bits(VertexId id, const StreamContext& context);
// Width of the depth field: enough for 0..node_id_bits.
uint32_t depth_field_bits(uint32_t node_id_bits);

}  // namespace pms::protocol
