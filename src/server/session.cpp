// One client's session of the sender-driven protocol (kim-lee-kobbelt §5.3): HELLO, LIST, OPEN (with
// resume), VIEW -> SelectiveStreaming in batches, CLOSE. The session holds a reference to its model
// and the windowed active tags; a VIEW's ranking lives only while that VIEW is being answered.
// A view-independent session (the baseline of §8, Fig. 9) streams the plain PM order instead: each VIEW
// extends the prefix of split_order sent up to the shortest one that satisfies the view.
// Every call is bounded: receive() decodes and records, pump() does one slice of what is pending.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>
#include <span>
#include <variant>

#include "server/server.h"

namespace pms::server {
namespace {

using protocol::ErrorCode;
using protocol::ProtocolError;

}  // namespace

// Resume (kim-lee-kobbelt §5.3 "Session close"): the client's known leaves are the front. Two passes
// over the coded front: the first checks every leaf and finds the window it spans, the second sets the
// tags in a window sized once (leaves come in preorder, whose node indices jump back and forth).
struct Session::Resume {
  Resume(std::vector<uint8_t> front, const protocol::OpenHeader& h, uint64_t max_leaves)
      : payload(std::move(front)), header(h), decoder(payload, header, max_leaves) {}

  std::vector<uint8_t> payload;
  protocol::OpenHeader header;
  protocol::FrontDecoder decoder;
  bool checked = false;  // the first pass is done
  uint32_t lo = UINT32_MAX, hi = 0;
  ActiveTags tags;
  std::vector<VertexId> leaves;  // one slice's
};

// View-independent mode: the shortest prefix of split_order whose front satisfies the view.
// SelectiveStreaming on a copy of the tags (the front of the prefix sent) collects every split the view
// wants there, partial-order dependencies included; the furthest of them in PM order ends the prefix.
// The PM order makes other splits on the way, whose children the view may want in turn, so the walk
// repeats from the new prefix's front until it wants nothing (each round only moves the end right).
struct Session::ViewPrefix {
  enum class Phase { walking, advancing, streaming };
  Phase phase = Phase::walking;
  ActiveTags front;  // the front of split_order[0, end) plus what the walk split
  SelectiveStreamer walk;
  std::vector<uint32_t> wanted;  // one slice's
  bool wanted_any = false;
  uint64_t end = 0, furthest = 0, next = 0;
};

Session::Session(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits)
    : catalogue_(std::move(catalogue)), limits_(limits) {}

Session::~Session() = default;

void Session::queue(std::vector<uint8_t> frame) {
  outbox_.push_back(std::make_shared<const std::vector<uint8_t>>(std::move(frame)));
}

void Session::abort_with(ErrorCode code, const std::string& text) {
  if (closing_) return;
  streamer_.stop();
  resume_.reset();
  prefix_.reset();
  view_pending_ = false;
  error_ = code;
  error_text_ = text;
  // The ERROR text is the peer's to read, never over its frame limit.
  queue(protocol::encode(protocol::ErrorMessage{code, text.substr(0, 512)}));
  closing_ = true;
}

// Anything but a protocol error is the server's fault: the session ends, the process goes on.
void Session::fault(const char* what) {
  if (closing_) return;
  try {
    abort_with(ErrorCode::internal, std::string("internal error: ") + what);
  } catch (const std::bad_alloc&) {  // no memory even for the ERROR: end without it
    outbox_.clear();
    error_ = ErrorCode::internal;
    closing_ = true;
  }
}

void Session::receive(protocol::Frame frame) {
  last_work_ = 0;
  if (closing_) return;
  try {
    handle(frame);
  } catch (const ProtocolError& e) {
    abort_with(e.code, e.what());
  } catch (const Error& e) {
    abort_with(ErrorCode::bad_message, e.what());
  } catch (const std::exception& e) {
    fault(e.what());
  }
}

void Session::handle(protocol::Frame& frame) {
  if (frame.type == protocol::MessageType::open) {  // its front is decoded by pump(), a slice at a time
    if (!greeted_) throw ProtocolError(ErrorCode::out_of_order, "OPEN before HELLO");
    on_open(protocol::decode_open_header(frame.payload), frame);
    return;
  }
  const protocol::ClientMessage message = protocol::decode_client_message(frame);
  if (!greeted_ && !std::holds_alternative<protocol::Hello>(message))
    throw ProtocolError(ErrorCode::out_of_order, protocol::to_string(frame.type) + " before HELLO");
  if (const auto* hello = std::get_if<protocol::Hello>(&message)) {
    on_hello(*hello);
  } else if (std::holds_alternative<protocol::List>(message)) {
    outbox_.push_back(catalogue_->catalogue_frame());
  } else if (const auto* view = std::get_if<protocol::View>(&message)) {
    on_view(*view);
  } else {  // CLOSE
    streamer_.stop();
    closing_ = true;
  }
}

void Session::on_hello(const protocol::Hello& m) {
  if (greeted_) throw ProtocolError(ErrorCode::out_of_order, "HELLO: sent twice");
  if (m.version != protocol::kProtocolVersion)
    throw ProtocolError(ErrorCode::unsupported_version,
                        "HELLO: protocol version " + std::to_string(m.version) + " (this server speaks " +
                            std::to_string(protocol::kProtocolVersion) + ")");
  greeted_ = true;
  protocol::HelloOk ok;
  ok.server_name = "pmstream";
  ok.max_client_message = limits_.max_client_message;
  ok.max_server_message = limits_.max_server_message;
  queue(protocol::encode(ok));
}

void Session::on_open(const protocol::OpenHeader& m, protocol::Frame& frame) {
  if (model_) throw ProtocolError(ErrorCode::out_of_order, "OPEN: a model is already open in this session");
  const ServedModel* model = catalogue_->find(m.model);
  if (!model) throw ProtocolError(ErrorCode::unknown_model, "OPEN: no model named '" + m.model + "'");
  if (m.mode == protocol::StreamMode::view_independent && m.resume)
    throw ProtocolError(ErrorCode::bad_message,
                        "OPEN: resume: a view-independent session cannot resume (sender-driven only)");
  const uint32_t roots = model->view().root_count;
  if (m.resume && m.resume_trees != roots)
    throw ProtocolError(ErrorCode::bad_id, "OPEN: resume: the front covers " + std::to_string(m.resume_trees) +
                                               " trees, the model has " + std::to_string(roots));
  model_ = model;
  mode_ = m.mode;
  context_ = model->context;
  context_.has_refinement = mode_ == protocol::StreamMode::sender_driven;
  if (m.resume) {
    resume_ = std::make_unique<Resume>(std::move(frame.payload), m, protocol::kDefaultMaxResumeLeaves);
    return;
  }
  tags_ = ActiveTags(roots);
  outbox_.push_back(model->base_frame);
}

void Session::on_view(const protocol::View& m) {
  if (!model_) throw ProtocolError(ErrorCode::out_of_order, "VIEW before OPEN");
  const ModelView& model = model_->view();
  // The same derivation as the client's, from the same box: bit-identical criteria on both ends.
  view_ = make_criteria(make_view(m.camera, model.bbox_min, model.bbox_max), m.tolerance);
  view_frame_ = m.frame;
  view_pending_ = true;
  restart_ = true;  // pump() starts the answer once, however many VIEWs came before it
}

bool Session::has_work() const { return !closing_ && (resume_ || view_pending_); }

bool Session::pump() {
  last_work_ = 0;
  if (!has_work()) return false;
  try {
    if (resume_) return pump_resume(last_work_);
    if (mode_ == protocol::StreamMode::view_independent) return pump_view_independent(last_work_);
    return pump_sender(last_work_);
  } catch (const ProtocolError& e) {
    abort_with(e.code, e.what());
  } catch (const std::exception& e) {
    fault(e.what());
  }
  return true;
}

bool Session::pump_resume(uint64_t& work) {
  Resume& r = *resume_;
  const ModelView& view = model_->view();
  r.leaves.clear();
  const bool decoded = r.decoder.next(limits_.slice_work, r.leaves);
  work += r.leaves.size();
  for (const VertexId& id : r.leaves) {
    const uint32_t node = view.find(id);
    if (!r.checked) {
      if (node == kNone)
        throw ProtocolError(ErrorCode::bad_id, "OPEN: resume id " + to_string(id) + " is not in the model");
      r.lo = std::min(r.lo, node);
      r.hi = std::max(r.hi, node);
    } else {
      r.tags.activate(node);
    }
  }
  if (!decoded) return true;
  if (!r.checked) {  // every leaf is a node of the model: now set them
    r.checked = true;
    r.tags.reserve_window(r.lo, r.hi);
    r.decoder = protocol::FrontDecoder(r.payload, r.header, protocol::kDefaultMaxResumeLeaves);
    return true;
  }
  tags_ = std::move(r.tags);
  resume_.reset();
  outbox_.push_back(model_->base_frame);
  return true;
}

// The first `count` splits of the batch (a VSPLITS never holds more than batch_splits: a dependency chain
// can carry the batch past it, and the rest waits for the next frame, in order).
void Session::emit_batch(size_t count, bool final) {
  queue(model_->packets.encode(*view_frame_, final, std::span(batch_).first(count)));
  splits_sent_ += count;
  batch_.erase(batch_.begin(), batch_.begin() + ptrdiff_t(count));
}

const Importance& Session::importance() {
  if (!importance_) {
    const std::vector<NodeCriteria>& criteria = model_->criteria;
    importance_ = [this, &criteria](uint32_t node) { return refinement_priority(view_, criteria[node]); };
  }
  return importance_;
}

// A VIEW's answer: splits accumulate across slices into batches of batch_splits. Splits of an earlier
// VIEW still in the batch go out with the new one's frame number (the client applies every batch).
bool Session::pump_sender(uint64_t& work) {
  if (restart_) {
    restart_ = false;
    streamer_.start(model_->view(), model_->dependencies, tags_, importance());
  }
  const size_t limit = limits_.batch_splits;
  const size_t room = batch_.size() < limit ? limit - batch_.size() : 0;
  const bool served = streamer_.step(room, limits_.slice_work, batch_, work);
  while (batch_.size() > limit || (batch_.size() == limit && !served)) emit_batch(limit, false);
  if (served) {
    streamer_.stop();
    view_pending_ = false;
    emit_batch(batch_.size(), true);
  }
  return true;
}

bool Session::pump_view_independent(uint64_t& work) {
  using Phase = ViewPrefix::Phase;
  const ModelView& model = model_->view();
  if (restart_) {
    restart_ = false;
    if (!prefix_) prefix_ = std::make_unique<ViewPrefix>();
    ViewPrefix& p = *prefix_;
    p.phase = Phase::walking;
    p.front = tags_;
    p.end = sent_;
    p.wanted_any = false;
    p.walk.start(model, model_->dependencies, p.front, importance());
  }
  ViewPrefix& p = *prefix_;
  if (p.phase == Phase::walking) {
    p.wanted.clear();
    const bool served = p.walk.step(SIZE_MAX, limits_.slice_work, p.wanted, work);
    if (!p.wanted.empty() && !p.wanted_any) {
      p.wanted_any = true;
      p.furthest = p.end;
    }
    for (uint32_t node : p.wanted) p.furthest = std::max<uint64_t>(p.furthest, uint64_t(model_->split_rank[node]) + 1);
    if (!served) return true;
    p.walk.stop();
    p.phase = p.wanted_any ? Phase::advancing : Phase::streaming;
    p.next = p.end;
    return true;
  }
  if (p.phase == Phase::advancing) {
    // The rest of the prefix, so `front` is again the front of split_order[0, furthest).
    const uint64_t begin = p.next, stop = std::min<uint64_t>(p.furthest, p.next + limits_.slice_work);
    for (; p.next < stop; ++p.next) {
      const uint32_t node = model.split_order[p.next];
      if (!p.front.is_active(node)) continue;  // split above as one the view wanted
      p.front.deactivate(node);
      p.front.activate(model.first_child[node]);
      p.front.activate(model.first_child[node] + 1);
    }
    work += stop - begin;
    if (p.next < p.furthest) return true;
    p.end = p.furthest;
    p.wanted_any = false;
    p.phase = Phase::walking;
    p.walk.start(model, model_->dependencies, p.front, importance());
    return true;
  }
  // Streaming split_order[sent_, end) in PM order; the last (possibly empty) batch is final.
  const uint64_t stop = std::min<uint64_t>({p.end, sent_ + limits_.batch_splits, sent_ + limits_.slice_work});
  protocol::VSplits message;
  message.frame = *view_frame_;
  message.final = stop >= p.end;
  message.splits.reserve(size_t(stop - sent_));
  for (; sent_ < stop; ++sent_) {
    const uint32_t node = model.split_order[sent_];
    tags_.deactivate(node);
    tags_.activate(model.first_child[node]);
    tags_.activate(model.first_child[node] + 1);
    message.splits.push_back(split_record(model, node));
  }
  work += message.splits.size();
  queue(protocol::encode(message, context_));
  splits_sent_ += message.splits.size();
  if (message.final) {
    view_pending_ = false;
    prefix_.reset();  // its copy of the tags is only needed while a VIEW is answered
  }
  return true;
}

size_t Session::state_bytes() const {
  size_t bytes = sizeof(*this) + tags_.memory_bytes() + streamer_.memory_bytes() + batch_.capacity() * sizeof(uint32_t);
  if (resume_)
    bytes += sizeof(Resume) + resume_->payload.capacity() + resume_->tags.memory_bytes() +
             resume_->leaves.capacity() * sizeof(VertexId);
  if (prefix_)
    bytes += sizeof(ViewPrefix) + prefix_->front.memory_bytes() + prefix_->walk.memory_bytes() +
             prefix_->wanted.capacity() * sizeof(uint32_t);
  return bytes;
}

}  // namespace pms::server
