// What a client sends (docs/protocol.md): HELLO, LIST, OPEN (with a resume front), VIEW, CLOSE, DAG_VIEW, and
// their codecs.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/camera.h"
#include "dag/traversal.h"
#include "protocol/message_types.h"
#include "protocol/stream_mode.h"
#include "spm/vertex_id.h"

namespace pms::protocol {

struct Hello {
  uint16_t version = kProtocolVersion;
  std::string client_name;
};
struct List {};
// `resume`: the leaves of the partial hierarchy the client already holds (everything it received in an
// earlier session: docs/architecture.md, "Scale-out"), so the server's active tags can be rebuilt and no
// vsplit is sent twice.
// Empty = a fresh session. A non-empty list must be a complete front of trees 0..R-1 (every root-to-leaf
// path meets exactly one listed id): the client's known leaves always are. It travels as a preorder
// split/leaf bit code (about 2 bits per leaf, not ~40).
// `mode`: what the server streams in this session (stream_mode.h).
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
// AHEAD (version 7, sender-driven sessions): the view the client expects to reach, extrapolated from its
// last cameras, for the server to stream at low priority while it has nothing else to send (kim-lee-kobbelt
// §9's idle time). Its fields and checks are VIEW's; its frame is echoed by the ahead VSPLITS it causes.
struct Ahead {
  View view;
};
// DAG_VIEW (StreamMode::dag): the view as VIEW carries it and MANAGE-TRAVERSAL's parameters (zheng-chan
// §4): N, the traversal, FREE or BUDGET and the budget. Bounded so one message asks for bounded work.
constexpr uint32_t kMaxDagOps = 65536;
constexpr uint64_t kMaxDagBudget = uint64_t(1) << 32;
struct DagView {
  View view;
  uint32_t max_ops = 300;  // N, 1..kMaxDagOps
  DagTraversal traversal = DagTraversal::priority;
  DagMode management = DagMode::free;
  uint64_t budget = 0;  // triangles: 1..kMaxDagBudget in BUDGET mode, 0 in FREE mode
};

// The traversals by the names every front end uses (`stream --traversal`, the page's DAG panel and URL):
// "priority", "linear", "constant"; nullopt for any other. A budget > 0 picks BUDGET mode, not a name.
std::optional<DagTraversal> dag_traversal_named(std::string_view name);
const char* dag_traversal_name(DagTraversal traversal);
constexpr const char* kDagTraversalNames = "priority, linear or constant";

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

// ---- encoders: each returns a whole frame (header + payload) -------------------------------------------
// They throw pms::Error for values the format cannot carry (a name over kMaxNameBytes, an id beyond the
// context's widths, a resume list that is not a front).
std::vector<uint8_t> encode(const Hello& m);
std::vector<uint8_t> encode(const List& m);
std::vector<uint8_t> encode(const Open& m);
std::vector<uint8_t> encode(const View& m);
std::vector<uint8_t> encode(const Close& m);
std::vector<uint8_t> encode(const DagView& m);

// ---- decoders: payload (without the frame header) -> message; throw ProtocolError ----------------------
Hello decode_hello(std::span<const uint8_t> payload);  // checks the magic; the version is the server's call
List decode_list(std::span<const uint8_t> payload);
Open decode_open(std::span<const uint8_t> payload, uint64_t max_resume_leaves = kDefaultMaxResumeLeaves);
OpenHeader decode_open_header(std::span<const uint8_t> payload);  // the front is left to a FrontDecoder
std::vector<uint8_t> encode(const Ahead& m);
Ahead decode_ahead(std::span<const uint8_t> payload);  // VIEW's checks
View decode_view(std::span<const uint8_t> payload);               // also rejects cameras make_view() would refuse
Close decode_close(std::span<const uint8_t> payload);
DagView decode_dag_view(std::span<const uint8_t> payload);  // the checks of VIEW and the bounds above

}  // namespace pms::protocol
