// The client's side of a fuzzed server session (fuzz_session.cpp). Expectation follows what the session
// was sent and says which ERROR codes, if any, it may end with; SimulatedClient reads the outbox as a real
// client would (decode with the context of the BASE it saw, apply every split to the leaves it holds) and
// checks each promise of docs/protocol.md on the way. In the DAG mode it keeps the client's mesh as a DagCut
// over the served model's DAG (the mirror of the session's cut) and applies every DAG_OPS operation to it with
// DagCut's own checks. A broken promise is a finding: fail() says which and traps, so libFuzzer keeps the input.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "common/error.h"
#include "dag/cut.h"
#include "dag/dag.h"
#include "dag/traversal.h"
#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/dag_mode.h"
#include "server/limits.h"
#include "server/session.h"
#include "spm/hierarchy.h"
#include "spm/split_codec.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

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

// The cut whose mesh has the vertices `front` (a complete front of the model's trees, each a model node; empty:
// the base mesh), or none when that mesh is no cut of the DAG: what a DAG session's resume must rebuild or refuse.
inline std::optional<DagCut> cut_of_front(const ModelData& model, const Dag& dag, const std::vector<VertexId>& front) {
  std::vector<uint32_t> split;
  for (const VertexId& id : front) append_closed_splits(model, dag, model.find(id), split);
  try {
    return DagCut(dag, split);
  } catch (const Error&) {
    return std::nullopt;
  }
}

class SimulatedClient {
 public:
  SimulatedClient(const ModelData& model, const Dag& dag, const server::ServerLimits& limits)
      : model_(model), dag_(dag), limits_(limits), held_(model.node_count(), 0) {}

  // A new connection: what the old one queued and the client did not read is lost; the leaves stay.
  void reconnect() { s_ = {}; }
  void hello_sent(uint16_t version) {
    s_.greeted = true;
    s_.version = version;
  }
  void list_sent() { ++s_.lists; }
  // The session has every reason to accept this OPEN: BASE must come, and start from `front` (the roots
  // of a fresh session).
  void open_accepted(protocol::StreamMode mode, const std::vector<VertexId>& front) {
    s_.mode = mode;
    s_.front = front;
  }
  void ahead_sent(uint32_t frame) { s_.aheads.push_back(frame); }
  void view_sent(uint32_t frame) {
    // Frame numbers tell answers apart only while no two VIEWs share one.
    if (std::find(s_.views.begin(), s_.views.end(), frame) != s_.views.end()) s_.frames_distinct = false;
    s_.views.push_back(frame);
    s_.last_answered = false;
  }
  void dag_view_sent(const protocol::DagView& view) {
    view_sent(view.view.frame);
    s_.dag_views.push_back(view);
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
  // What the client resumes with: the vertices of its mesh in the DAG mode (DagClient::resume_front), else the
  // leaves it knows.
  std::vector<VertexId> resume_front() const {
    if (front_mode_ == protocol::StreamMode::dag) return cut_front(model_, *cut_);
    std::vector<VertexId> out;
    for (uint32_t n = 0; n < model_.node_count(); ++n)
      if (held_[n]) out.push_back(model_.id(n));
    return out;
  }
  protocol::StreamMode mode() const { return front_mode_; }  // of the session the leaves came from
  std::optional<protocol::ErrorCode> error() const { return s_.error; }
  // After BASE, whether the CODEC the session owes has come.
  bool codec_pending() const { return s_.context && !s_.context->records && protocol::carries_split_records(s_.mode); }
  const std::string& error_text() const { return s_.error_text; }

  // The session went quiet after every frame was read: each request has had its answer, and the server's
  // tags are exactly the leaves this client holds (kim-lee-kobbelt §6.1: the server keeps the client's front).
  void check_answered(const server::Session& session) const {
    check(!s_.greeted || s_.hello_oks == 1, "HELLO got no HELLO_OK");
    check(s_.catalogues == s_.lists, "a LIST got no CATALOGUE");
    if (!s_.front) return;
    check(s_.context.has_value(), "an accepted OPEN got no BASE");
    check(!codec_pending(), "a BASE of a session with split records got no CODEC");
    if (!s_.views.empty() && s_.frames_distinct)
      check(s_.last_answered, "the last VIEW's answer did not end with a final VSPLITS");
    check(session.splits_sent() == s_.splits, "splits_sent() is not what the client received");
    if (s_.mode == protocol::StreamMode::dag) return check_cut(session);
    const ActiveTags tags = session.front_tags();  // decoded when the session parked it
    for (uint32_t n = 0; n < model_.node_count(); ++n)
      if (tags.is_active(n) != bool(held_[n]))
        fail("the session's tags differ from the client's leaves at " + to_string(model_.id(n)));
  }

 private:
  // The DAG answer being read: the limits of the DAG_VIEW it answers (when that one is known, else the loosest
  // of the candidates) and what it has made so far.
  struct DagAnswer {
    uint32_t frame = 0;
    std::optional<uint64_t> budget;                     // BUDGET mode's
    std::optional<uint32_t> max_collapses, max_splits;  // N, from the session's second answer on
    uint32_t collapses = 0, splits = 0;
  };
  struct PerSession {
    bool greeted = false;
    uint16_t version = 0;          // the HELLO's: the session's HELLO_OK echoes it
    std::vector<uint32_t> aheads;  // every AHEAD's frame: an ahead VSPLITS names one
    uint32_t hello_oks = 0, lists = 0, catalogues = 0;
    protocol::StreamMode mode = protocol::StreamMode::sender_driven;
    std::optional<std::vector<VertexId>> front;  // of the OPEN the session must accept
    std::optional<protocol::StreamContext> context;
    std::vector<uint32_t> views;
    bool frames_distinct = true;
    bool last_answered = false;  // the latest VIEW's final VSPLITS arrived
    uint64_t splits = 0;
    std::vector<protocol::DagView> dag_views;  // every DAG_VIEW sent, in order
    size_t unanswered = 0;      // dag_views before this one were answered or replaced: an answer is to a later one
    bool dag_answered = false;  // the converged first answer is behind (or the resumed cut has a split): N applies
    std::optional<DagAnswer> answer;
    std::optional<protocol::ErrorCode> error;
    std::string error_text;
  };

  void on(const protocol::HelloOk& m) {
    trace([] { return "<- HELLO_OK"; });
    check(s_.greeted && s_.hello_oks++ == 0, "a HELLO_OK that answers no HELLO");
    check(m.version == s_.version, "HELLO_OK with another version than the HELLO's");
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
    has_front_ = true;
    front_mode_ = s_.mode;
    if (s_.mode == protocol::StreamMode::dag) {
      // The session's cut: the base mesh, or the resumed one (Expectation has checked it is a cut).
      cut_ = cut_of_front(model_, dag_, *s_.front);
      check(cut_.has_value(), "a BASE for a resume front that is no cut of the DAG");
      s_.dag_answered = cut_->split_count() > 0;
      return;
    }
    std::fill(held_.begin(), held_.end(), 0);
    if (s_.front->empty()) std::fill(held_.begin(), held_.begin() + model_.root_count, 1);
    for (const VertexId& id : *s_.front) held_[model_.find(id)] = 1;
  }
  void on(const protocol::VSplits& m) {
    trace([&] {
      return "<- VSPLITS frame " + std::to_string(m.frame) + (m.final ? " final, " : ", ") +
             std::to_string(m.splits.size()) + " splits";
    });
    if (m.ahead) {  // held splits of the leaves the client holds, answering no VIEW
      check(std::find(s_.aheads.begin(), s_.aheads.end(), m.frame) != s_.aheads.end() && !m.final,
            "an ahead VSPLITS for a frame no AHEAD named, or final");
      check(m.splits.size() <= limits_.batch_splits, "an ahead VSPLITS batch over batch_splits");
      for (const SplitRecord& split : m.splits) apply(split);
      return;
    }
    check(!s_.views.empty() && std::find(s_.views.begin(), s_.views.end(), m.frame) != s_.views.end(),
          "a VSPLITS for a frame no VIEW named");
    check(!(s_.frames_distinct && s_.last_answered), "a VSPLITS after the last VIEW's answer was final");
    if (m.splits.size() > limits_.batch_splits)
      fail("a VSPLITS batch of " + std::to_string(m.splits.size()) + " splits, over batch_splits " +
           std::to_string(limits_.batch_splits));
    for (const SplitRecord& split : m.splits) apply(split);
    if (m.final && m.frame == s_.views.back()) s_.last_answered = true;
  }
  // A session whose packets are split records gets the tables right after BASE; the packets then decode
  // against what this client holds, which for a held node of the model is the model's own context.
  void on(const protocol::Codec& m) {
    trace([] { return "<- CODEC"; });
    check(s_.context.has_value() && !s_.context->records, "a CODEC that follows no BASE, or a second one");
    check(protocol::carries_split_records(s_.mode), "a CODEC in a session without split records");
    if (positions_.empty()) positions_ = grid_positions(model_, s_.context->grid.bits);
    s_.context->records = m.codec;
    s_.context->held = [this](VertexId id, SplitContext& out) {
      const uint32_t node = model_.find(id);
      if (node == kNone || !held_[node] || model_.is_leaf(node)) return false;
      out = split_context(model_, positions_, node);
      return true;
    };
  }
  // A DAG answer's operations go to the mirror as the client applies them (ClientSession::apply_dag_ops: each
  // batch's collapses, then its splits); each must be legal there, and the answer within its DAG_VIEW's limits.
  void on(const protocol::DagOps& m) {
    trace([&] {
      return "<- DAG_OPS frame " + std::to_string(m.frame) + (m.final ? " final, " : ", ") +
             std::to_string(m.collapses.size()) + " collapses, " + std::to_string(m.splits.size()) + " splits";
    });
    check(s_.mode == protocol::StreamMode::dag && cut_, "a DAG_OPS in a session not in the DAG mode");
    check(!(s_.frames_distinct && s_.last_answered), "a DAG_OPS after the last DAG_VIEW's answer was final");
    check(m.collapses.size() + m.splits.size() <= limits_.batch_splits, "a DAG_OPS batch over batch_splits");
    if (!s_.answer) start_answer(m.frame);
    DagAnswer& a = *s_.answer;
    check(m.frame == a.frame, "a DAG_OPS of another frame before the answer it interrupts was final");
    for (const VertexId& id : m.collapses) dag_collapse(id);
    for (const SplitRecord& split : m.splits) dag_split(split, a.budget);
    a.collapses += uint32_t(m.collapses.size());
    a.splits += uint32_t(m.splits.size());
    if (a.max_collapses && a.collapses > *a.max_collapses)
      fail("an answer of " + std::to_string(a.collapses) + " collapses, over its N " +
           std::to_string(*a.max_collapses));
    if (a.max_splits && a.splits > *a.max_splits)
      fail("an answer of " + std::to_string(a.splits) + " splits, over its N " + std::to_string(*a.max_splits));
    if (!m.final) return;
    s_.answer.reset();
    if (m.frame == s_.views.back()) s_.last_answered = true;
  }
  void on(const protocol::ErrorMessage& m) {
    trace([&] { return "<- ERROR " + protocol::to_string(m.code) + ": " + m.text; });
    check(m.code != protocol::ErrorCode::internal, "ERROR internal: the server's own fault");
    s_.error = m.code;
    s_.error_text = m.text;
  }

  // An answer is to the latest DAG_VIEW the session had when it traversed: one after the previous answer's,
  // naming this frame. With frame numbers repeated several may fit; the checks take the loosest of their limits.
  // The first answer is the converged cut, bounded by kMaxDagOps only (docs/internals.md, "The DAG mode"); from
  // the second on, priority and linear make at most N collapses and N splits, constant-time evaluates at most N
  // nodes (so at most N collapses; its forced splits are not evaluated).
  void start_answer(uint32_t frame) {
    DagAnswer a;
    a.frame = frame;
    bool named = false, free = false, unlimited_splits = false;
    uint32_t n = 0;
    for (size_t i = s_.unanswered; i < s_.dag_views.size(); ++i) {
      const protocol::DagView& v = s_.dag_views[i];
      if (v.view.frame != frame) continue;
      if (!named) s_.unanswered = i + 1;
      named = true;
      if (v.management == DagMode::budget) a.budget = std::max(a.budget.value_or(0), v.budget);
      else free = true;
      unlimited_splits |= v.traversal == DagTraversal::constant_time;
      n = std::max(n, v.max_ops);
    }
    if (!named)
      fail("a DAG_OPS for frame " + std::to_string(frame) + ", which no DAG_VIEW since the last answer named");
    if (free) a.budget.reset();
    if (s_.dag_answered) {
      a.max_collapses = n;
      if (!unlimited_splits) a.max_splits = n;
    }
    s_.dag_answered = true;
    s_.answer = a;
  }
  uint32_t dag_node(const VertexId& v, const char* what) const {
    const uint32_t node = model_.find(v);
    if (node == kNone || model_.is_leaf(node))
      fail(std::string(what) + " of " + to_string(v) + ", which the model does not split");
    return dag_.node_of(node);
  }
  void dag_collapse(const VertexId& v) {
    const uint32_t n = dag_node(v, "a collapse");
    if (!cut_->in_fc(n)) fail("a collapse of " + to_string(v) + ", not in Fc of the client's cut");
    cut_->collapse(n);
  }
  // A split is of a node in Fs with the model's geometry and fundamental cut vertices (docs/internals.md, "The DAG
  // mode"); in BUDGET mode one that adds triangles leaves the cut within the budget: the traversal's room is the
  // budget less the cut after the collapses, so a split never takes the cut over it, and from a cut over it (a
  // lower budget than the last answer's) only collapses come.
  void dag_split(const SplitRecord& split, std::optional<uint64_t> budget) {
    const uint32_t n = dag_node(split.vs, "a split");
    if (!cut_->in_fs(n)) fail("a split of " + to_string(split.vs) + ", not in Fs of the client's cut");
    const uint32_t node = dag_.model_node(n);
    check(split.cut_l == cut_id(model_.cut_left[node]) && split.cut_r == cut_id(model_.cut_right[node]),
          "a DAG split's cut vertices are not the model's");
    check_payload(split, model_.first_child[node]);
    cut_->split(n);
    ++s_.splits;
    if (budget && dag_.faces(n) > 0 && cut_->triangles() > *budget)
      fail("a split takes the cut to " + std::to_string(cut_->triangles()) + " triangles, over the budget " +
           std::to_string(*budget));
  }
  // The session went quiet: its cut is the client's mesh.
  void check_cut(const server::Session& session) const {
    const auto* mode = dynamic_cast<const server::DagSessionMode*>(session.session_mode());
    check(mode && mode->opened(), "a DAG session with no cut");
    const DagCut theirs = mode->cut().dense(dag_);
    std::string why;
    if (!cut_->check(&why)) fail("the client's cut: " + why);
    check(theirs.triangles() == cut_->triangles(), "the session's cut has other triangles than the client's mesh");
    for (uint32_t n = 0; n < dag_.size(); ++n)
      if (theirs.is_split(n) != cut_->is_split(n))
        fail("the session's cut differs from the client's mesh at " + to_string(model_.id(dag_.model_node(n))));
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
  const Dag& dag_;
  const server::ServerLimits& limits_;
  std::vector<uint8_t> held_;        // per node: a leaf of the client's partial hierarchy
  std::optional<DagCut> cut_;        // the DAG mode: the client's mesh, once a DAG session's BASE came
  std::vector<uint32_t> positions_;  // the model's on the wire grid, for split record contexts
  bool has_front_ = false;           // a BASE arrived in this or an earlier session
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
  Expectation(const ModelData& model, const Dag& dag, const std::string& name)
      : model_(model), dag_(dag), name_(name) {}

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
      if (hello->version < protocol::kMinProtocolVersion || hello->version > protocol::kProtocolVersion)
        return allow(ErrorCode::unsupported_version);
      greeted_ = true;
      version_ = hello->version;
      client.hello_sent(hello->version);
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
      if (!open_ || mode_ == protocol::StreamMode::dag) return allow(ErrorCode::out_of_order);
      return client.view_sent(view->frame);
    }
    if (const auto* ahead = std::get_if<protocol::Ahead>(&message)) {
      trace([&] { return "   AHEAD " + std::to_string(ahead->view.frame); });
      // Version 7's, in a sender-driven session only (a plain one makes every split it gets).
      if (!open_ || mode_ != protocol::StreamMode::sender_driven || version_ < 7) return allow(ErrorCode::out_of_order);
      return client.ahead_sent(ahead->view.frame);
    }
    if (const auto* view = std::get_if<protocol::DagView>(&message)) {
      trace([&] {
        return "   DAG_VIEW " + std::to_string(view->view.frame) + ": traversal " +
               std::to_string(int(view->traversal)) +
               (view->management == DagMode::budget ? ", budget " + std::to_string(view->budget) : ", free") + ", N " +
               std::to_string(view->max_ops) + ", tolerance " + std::to_string(view->view.tolerance) + " px";
      });
      // Only a DAG session takes it, and a sender-driven one only VIEW.
      if (!open_ || mode_ != protocol::StreamMode::dag) return allow(ErrorCode::out_of_order);
      return client.dag_view_sent(*view);
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
    mode_ = open.mode;
    if (!open.resume.empty() && open.mode == protocol::StreamMode::view_independent)
      return allow(ErrorCode::bad_message);
    if (!covers_model(open.resume)) {
      allow(ErrorCode::bad_id);
      return allow(ErrorCode::too_large);  // a front longer than the model's leaves may be refused as such
    }
    // A DAG session's front is the client's mesh: it resumes when that is a cut of the DAG.
    if (open.mode == protocol::StreamMode::dag && !cut_of_front(model_, dag_, open.resume))
      return allow(ErrorCode::bad_id);
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
  const Dag& dag_;
  std::string name_;
  bool greeted_ = false, open_ = false, closed_ = false;
  uint16_t version_ = 0;
  protocol::StreamMode mode_ = protocol::StreamMode::sender_driven;  // of the OPEN taken
  std::vector<protocol::ErrorCode> allowed_;
};

}  // namespace pms::fuzz
