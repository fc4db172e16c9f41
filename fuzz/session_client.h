// The client's side of a fuzzed server session (fuzz_session.cpp). Expectation follows what the session
// was sent and says which ERROR codes, if any, it may end with; SimulatedClient reads the outbox as a real
// client would (decode with the context of the BASE it saw, apply every split to the leaves it holds) and
// checks each promise of docs/protocol.md on the way. A broken promise is a finding: fail() says which and
// traps, so libFuzzer keeps the input.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "pm/hierarchy.h"
#include "pm/split_record.h"
#include "pm/vertex_id.h"
#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/session.h"

namespace pms::fuzz {

[[noreturn]] inline void fail(const std::string& why) {
  std::fprintf(stderr, "fuzz_session: %s\n", why.c_str());
  std::fflush(stderr);
  __builtin_trap();
}

inline void check(bool ok, const char* why) {
  if (!ok) fail(why);
}

// PMSTREAM_FUZZ_TRACE=1 prints what a run does, to read a reproducer's story without a debugger. The line is
// only built when tracing: an allocation per call would cost more under ASan than the session's own work.
template <class Line>
void trace(Line&& line) {
  static const bool on = std::getenv("PMSTREAM_FUZZ_TRACE") != nullptr;
  if (on) std::fprintf(stderr, "  %s\n", std::string(line()).c_str());
}

class SimulatedClient {
 public:
  SimulatedClient(const ModelData& model, const server::ServerLimits& limits)
      : model_(model), limits_(limits), held_(model.node_count(), 0) {}

  // A new connection: what the old one queued and the client did not read is lost; the leaves stay.
  void reconnect() { s_ = {}; }
  void hello_sent() { s_.greeted = true; }
  void list_sent() { ++s_.lists; }
  // The session has every reason to accept this OPEN: BASE must come, and start from `front` (the roots
  // of a fresh session).
  void open_accepted(protocol::StreamMode mode, const std::vector<VertexId>& front) {
    s_.mode = mode;
    s_.front = front;
  }
  void view_sent(uint32_t frame) {
    // Frame numbers tell answers apart only while no two VIEWs share one.
    if (std::find(s_.views.begin(), s_.views.end(), frame) != s_.views.end()) s_.frames_distinct = false;
    s_.views.push_back(frame);
    s_.last_answered = false;
  }

  void read(const std::vector<uint8_t>& bytes) {
    check(bytes.size() >= protocol::kFrameHeaderBytes, "a frame shorter than its header");
    const uint32_t length =
        uint32_t(bytes[0]) | uint32_t(bytes[1]) << 8 | uint32_t(bytes[2]) << 16 | uint32_t(bytes[3]) << 24;
    check(length == bytes.size() - protocol::kFrameHeaderBytes, "a frame's length field is not its payload");
    if (length > limits_.max_server_message)
      fail(protocol::to_string(protocol::MessageType(bytes[4])) + " of " + std::to_string(length) +
           " payload bytes, over max_server_message " + std::to_string(limits_.max_server_message));
    check(!s_.error, "a frame after ERROR");
    protocol::Frame frame{protocol::MessageType(bytes[4]), {bytes.begin() + protocol::kFrameHeaderBytes, bytes.end()}};
    // Every session sends the same BASE bytes (one shared frame); decoding them again would find nothing new.
    if (frame.type == protocol::MessageType::base && bytes == last_base_bytes_) return on(last_base_);
    protocol::ServerMessage message;
    try {
      message = protocol::decode_server_message(frame, s_.context ? &*s_.context : nullptr);
    } catch (const protocol::ProtocolError& e) {
      fail(std::string("the client cannot decode what the session sent: ") + e.what());
    }
    if (const auto* base = std::get_if<protocol::Base>(&message)) {
      last_base_bytes_ = bytes;
      last_base_ = *base;
    }
    std::visit([this](const auto& m) { on(m); }, message);
  }

  bool has_front() const { return has_front_; }
  // The client's known leaves, to resume with.
  std::vector<VertexId> leaves() const {
    std::vector<VertexId> out;
    for (uint32_t n = 0; n < model_.node_count(); ++n)
      if (held_[n]) out.push_back(model_.id(n));
    return out;
  }
  protocol::StreamMode mode() const { return front_mode_; }  // of the session the leaves came from
  std::optional<protocol::ErrorCode> error() const { return s_.error; }
  const std::string& error_text() const { return s_.error_text; }

  // The session went quiet after every frame was read: each request has had its answer, and the server's
  // tags are exactly the leaves this client holds (kim-lee-kobbelt §6.1: the server keeps the client's front).
  void check_answered(const server::Session& session) const {
    check(!s_.greeted || s_.hello_oks == 1, "HELLO got no HELLO_OK");
    check(s_.catalogues == s_.lists, "a LIST got no CATALOGUE");
    if (!s_.front) return;
    check(s_.context.has_value(), "an accepted OPEN got no BASE");
    if (!s_.views.empty() && s_.frames_distinct)
      check(s_.last_answered, "the last VIEW's answer did not end with a final VSPLITS");
    check(session.splits_sent() == s_.splits, "splits_sent() is not what the client received");
    for (uint32_t n = 0; n < model_.node_count(); ++n)
      if (session.tags().is_active(n) != bool(held_[n]))
        fail("the session's tags differ from the client's leaves at " + to_string(model_.id(n)));
  }

 private:
  struct PerSession {
    bool greeted = false;
    uint32_t hello_oks = 0, lists = 0, catalogues = 0;
    protocol::StreamMode mode = protocol::StreamMode::sender_driven;
    std::optional<std::vector<VertexId>> front;  // of the OPEN the session must accept
    std::optional<protocol::StreamContext> context;
    std::vector<uint32_t> views;
    bool frames_distinct = true;
    bool last_answered = false;  // the latest VIEW's final VSPLITS arrived
    uint64_t splits = 0;
    std::optional<protocol::ErrorCode> error;
    std::string error_text;
  };

  void on(const protocol::HelloOk& m) {
    trace([] { return "<- HELLO_OK"; });
    check(s_.greeted && s_.hello_oks++ == 0, "a HELLO_OK that answers no HELLO");
    check(m.version == protocol::kProtocolVersion, "HELLO_OK with another version");
    check(m.max_client_message == limits_.max_client_message && m.max_server_message == limits_.max_server_message,
          "HELLO_OK announces other limits than the server's");
  }
  void on(const protocol::Catalogue& m) {
    trace([] { return "<- CATALOGUE"; });
    check(++s_.catalogues <= s_.lists, "a CATALOGUE that answers no LIST");
    check(m.models.size() == 1, "the CATALOGUE does not list the one model served");
  }
  void on(const protocol::Base& m) {
    trace([] { return "<- BASE"; });
    check(s_.front.has_value(), "a BASE for an OPEN the session should have refused");
    check(!s_.context, "a second BASE");
    check(m.root_count() == model_.root_count, "BASE with another root count than the model's");
    s_.context = protocol::stream_context(m);
    s_.context->has_refinement = s_.mode == protocol::StreamMode::sender_driven;
    std::fill(held_.begin(), held_.end(), 0);
    if (s_.front->empty()) std::fill(held_.begin(), held_.begin() + model_.root_count, 1);
    for (const VertexId& id : *s_.front) held_[model_.find(id)] = 1;
    has_front_ = true;
    front_mode_ = s_.mode;
  }
  void on(const protocol::VSplits& m) {
    trace([&] {
      return "<- VSPLITS frame " + std::to_string(m.frame) + (m.final ? " final, " : ", ") +
             std::to_string(m.splits.size()) + " splits";
    });
    check(!s_.views.empty() && std::find(s_.views.begin(), s_.views.end(), m.frame) != s_.views.end(),
          "a VSPLITS for a frame no VIEW named");
    check(!(s_.frames_distinct && s_.last_answered), "a VSPLITS after the last VIEW's answer was final");
    if (m.splits.size() > limits_.batch_splits)
      fail("a VSPLITS batch of " + std::to_string(m.splits.size()) + " splits, over batch_splits " +
           std::to_string(limits_.batch_splits));
    for (const SplitRecord& split : m.splits) apply(split);
    if (m.final && m.frame == s_.views.back()) s_.last_answered = true;
  }
  // The DAG mode's answers are checked for their size only (a raw OPEN can open a dag session this client
  // did not plan); mirroring the server's cut to check their operations is issue 16's next step here.
  void on(const protocol::DagOps& m) {
    trace([&] { return "<- DAG_OPS frame " + std::to_string(m.frame) + (m.final ? " final" : ""); });
    check(m.collapses.size() + m.splits.size() <= limits_.batch_splits, "a DAG_OPS batch over batch_splits");
  }
  void on(const protocol::ErrorMessage& m) {
    trace([&] { return "<- ERROR " + protocol::to_string(m.code) + ": " + m.text; });
    check(m.code != protocol::ErrorCode::internal, "ERROR internal: the server's own fault");
    s_.error = m.code;
    s_.error_text = m.text;
  }

  // UpdateVHierarchy (kim-lee-kobbelt §5.3) on the leaf set: v_s must be a leaf the client holds, or the
  // split was sent twice or before its parent's.
  void apply(const SplitRecord& split) {
    const uint32_t node = model_.find(split.vs);
    check(node != kNone && !model_.is_leaf(node), "a split of a node the model does not split");
    if (!held_[node]) fail("a split sent twice or out of order: " + to_string(split.vs) + " is not a held leaf");
    if (s_.mode == protocol::StreamMode::sender_plain) {
      // kim-lee-kobbelt §6.3: the cut vertices this client's mesh has, the held ancestors of the model's.
      check(split.cut_l == cut_id(held_ancestor_or_none(model_.cut_left[node])) &&
                split.cut_r == cut_id(held_ancestor_or_none(model_.cut_right[node])),
            "a plain split's cut vertices are not the client's actual ones");
    } else {
      check(split.cut_l == cut_id(model_.cut_left[node]) && split.cut_r == cut_id(model_.cut_right[node]),
            "a split's cut vertices are not the model's");
    }
    // SelStreamVSplit's partial order (§5.3): when both cut vertices hang below one held leaf, that leaf's
    // split must come first, or the client cannot apply this one.
    if (is_vertex(split.cut_l) && is_vertex(split.cut_r))
      check(held_ancestor(model_.cut_left[node]) != held_ancestor(model_.cut_right[node]),
            "a split before the split its cut vertices depend on");
    const uint32_t child = model_.first_child[node];
    check_payload(split, child);
    held_[node] = 0;
    held_[child] = held_[child + 1] = 1;
    ++s_.splits;
  }
  void check_payload(const SplitRecord& split, uint32_t child) const {
    uint32_t sent[3], model[3];
    protocol::quantize_position(s_.context->grid, split.position_t, sent);
    protocol::quantize_position(s_.context->grid, &model_.position[3 * child], model);
    check(sent[0] == model[0] && sent[1] == model[1] && sent[2] == model[2], "a split's position is not v_t's");
    if (s_.context->has_refinement)
      check(split.info_t == protocol::as_sent(model_.refine[child]) &&
                split.info_u == protocol::as_sent(model_.refine[child + 1]),
            "a split's refinement info is not its children's");
  }
  VertexId cut_id(uint32_t node) const { return node == kNone ? kNoVertex : model_.id(node); }
  uint32_t held_ancestor_or_none(uint32_t node) const { return node == kNone ? kNone : held_ancestor(node); }
  uint32_t held_ancestor(uint32_t node) const {
    while (node != kNone && !held_[node]) node = model_.parent[node];
    check(node != kNone, "the client's leaves are not a front");
    return node;
  }

  const ModelData& model_;
  const server::ServerLimits& limits_;
  std::vector<uint8_t> held_;  // per node: a leaf of the client's partial hierarchy
  bool has_front_ = false;     // a BASE arrived in this or an earlier session
  protocol::StreamMode front_mode_ = protocol::StreamMode::sender_driven;
  PerSession s_;
  std::vector<uint8_t> last_base_bytes_;
  protocol::Base last_base_;
};

// What a session may answer to what it was sent (docs/protocol.md): every frame it received is decoded
// here too, and the ERROR codes it can earn collect in `allowed`. An empty set means the session must end
// without an ERROR. Codes only add up: a resume front is checked by later pump() calls, so frames after a
// bad OPEN still reach the session and may end it first.
class Expectation {
 public:
  Expectation(const ModelData& model, const std::string& name) : model_(model), name_(name) {}

  void received(const protocol::Frame& frame, SimulatedClient& client) {
    using protocol::ErrorCode;
    protocol::ClientMessage message;
    try {
      message = protocol::decode_client_message(frame);
    } catch (const protocol::ProtocolError& e) {
      allow(e.code);
      allow(ErrorCode::out_of_order);  // the session may check the state before the payload
      if (frame.type == protocol::MessageType::open) {
        // Only the header is decoded on receipt; a leaf outside the model may precede the bad bits.
        for (ErrorCode c : {ErrorCode::bad_message, ErrorCode::bad_id, ErrorCode::unknown_model, ErrorCode::too_large})
          allow(c);
      }
      return;
    }
    if (!greeted_) {
      const auto* hello = std::get_if<protocol::Hello>(&message);
      if (!hello) return allow(ErrorCode::out_of_order);
      if (hello->version != protocol::kProtocolVersion) return allow(ErrorCode::unsupported_version);
      greeted_ = true;
      client.hello_sent();
      return;
    }
    if (std::holds_alternative<protocol::Hello>(message)) return allow(ErrorCode::out_of_order);
    if (std::holds_alternative<protocol::List>(message)) return client.list_sent();
    if (const auto* open = std::get_if<protocol::Open>(&message)) return opened(*open, client);
    if (const auto* view = std::get_if<protocol::View>(&message)) {
      const Camera& c = view->camera;
      trace([&] {
        return "   VIEW " + std::to_string(view->frame) + ": eye " + std::to_string(c.eye[0]) + " " +
               std::to_string(c.eye[1]) + " " + std::to_string(c.eye[2]) + ", target " + std::to_string(c.target[0]) +
               " " + std::to_string(c.target[1]) + " " + std::to_string(c.target[2]) + ", tolerance " +
               std::to_string(view->tolerance) + " px";
      });
      if (!open_) return allow(ErrorCode::out_of_order);
      return client.view_sent(view->frame);
    }
    closed_ = true;  // CLOSE: no answer, no error
  }
  void aborted(protocol::ErrorCode code) { allow(code); }

  bool must_fail() const { return !allowed_.empty(); }
  bool allows(protocol::ErrorCode code) const {
    return std::find(allowed_.begin(), allowed_.end(), code) != allowed_.end();
  }
  bool closed() const { return closed_; }

 private:
  void allow(protocol::ErrorCode code) {
    if (!allows(code)) allowed_.push_back(code);
  }
  void opened(const protocol::Open& open, SimulatedClient& client) {
    using protocol::ErrorCode;
    if (open_) return allow(ErrorCode::out_of_order);
    if (open.model != name_) return allow(ErrorCode::unknown_model);
    open_ = true;  // the session holds the model from here on, even while it checks a front it will refuse
    if (!open.resume.empty() && open.mode == protocol::StreamMode::view_independent)
      return allow(ErrorCode::bad_message);
    if (!covers_model(open.resume)) {
      allow(ErrorCode::bad_id);
      return allow(ErrorCode::too_large);  // a front longer than the model's leaves may be refused as such
    }
    client.open_accepted(open.mode, open.resume);
  }
  // The decoder returns a complete front of trees 0..R-1 in preorder: it is a cut of the model's forest
  // when R is the model's tree count and every leaf is a node of the model.
  bool covers_model(const std::vector<VertexId>& front) const {
    if (front.empty()) return true;
    if (front.back().tree + 1 != model_.root_count) return false;
    for (const VertexId& id : front)
      if (model_.find(id) == kNone) return false;
    return true;
  }

  const ModelData& model_;
  std::string name_;
  bool greeted_ = false, open_ = false, closed_ = false;
  std::vector<protocol::ErrorCode> allowed_;
};

}  // namespace pms::fuzz
