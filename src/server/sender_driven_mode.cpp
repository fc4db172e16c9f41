// The sender-driven mode: SelectiveStreaming over the session's active tags (kim-lee-kobbelt §5.3), and
// the resume of §5.3 "Session close".
#include "server/sender_driven_mode.h"

#include <algorithm>
#include <span>
#include <string>
#include <utility>
#include <variant>

#include "protocol/message_types.h"
#include "server/plain_packets.h"
#include "spm/hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::server {

using protocol::ErrorCode;
using protocol::ProtocolError;

// The client's known leaves are the front. Two passes over the coded front: the first checks every leaf
// and finds the window it spans, the second sets the tags in a window sized once (leaves come in preorder,
// whose node indices jump back and forth).
struct SenderDrivenMode::Resume {
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

SenderDrivenMode::SenderDrivenMode(const protocol::OpenHeader& open, protocol::Frame& open_frame,
                                   const ModeContext& context)
    : context_(context),
      importance_(view_.importance(context.served.tables->selective().criteria)),
      plain_(open.mode == protocol::StreamMode::sender_plain),
      plain_wire_(context.served.context),
      ahead_importance_(ahead_.importance(context.served.tables->selective().criteria)) {
  plain_wire_.has_refinement = false;
  const uint32_t roots = context_.served.model().root_count;
  if (!open.resume) {
    tags_ = ActiveTags(roots);
    park_if_due();
    queue_base();
    return;
  }
  if (open.resume_trees != roots)
    throw ProtocolError(ErrorCode::bad_id, "OPEN: resume: the front covers " + std::to_string(open.resume_trees) +
                                               " trees, the model has " + std::to_string(roots));
  resume_ = std::make_unique<Resume>(std::move(open_frame.payload), open, protocol::kDefaultMaxResumeLeaves);
}

SenderDrivenMode::~SenderDrivenMode() = default;

void SenderDrivenMode::receive(const protocol::ClientMessage& message) {
  if (const auto* ahead = std::get_if<protocol::Ahead>(&message)) {
    if (plain_) throw ProtocolError(ErrorCode::out_of_order, "AHEAD: a plain session makes every split it gets");
    ahead_.record(ahead->view, context_.served.model());
    return;
  }
  const auto* view = std::get_if<protocol::View>(&message);
  if (!view) throw ProtocolError(ErrorCode::out_of_order, "a sender-driven session takes only VIEW after OPEN");
  view_.record(*view, context_.served.model());
}

void SenderDrivenMode::pump(uint64_t& work) {
  if (resume_) return pump_resume(work);
  if (view_.pending) return pump_answer(work);
  if (ahead_due()) pump_ahead(work);
}

void SenderDrivenMode::stop() {
  stop_ahead();
  streamer_.stop();
  resume_.reset();
  view_.pending = false;
}

void SenderDrivenMode::pump_resume(uint64_t& work) {
  Resume& r = *resume_;
  const ModelData& model = context_.served.model();
  r.leaves.clear();
  const bool decoded = r.decoder.next(context_.limits.slice_work, r.leaves);
  work += r.leaves.size();
  for (const VertexId& id : r.leaves) {
    const uint32_t node = model.find(id);
    if (!r.checked) {
      if (node == kNone)
        throw ProtocolError(ErrorCode::bad_id, "OPEN: resume id " + to_string(id) + " is not in the model");
      r.lo = std::min(r.lo, node);
      r.hi = std::max(r.hi, node);
    } else {
      r.tags.activate(node);
    }
  }
  if (!decoded) return;
  if (!r.checked) {  // every leaf is a node of the model: now set them
    r.checked = true;
    r.tags.reserve_window(r.lo, r.hi);
    r.decoder = protocol::FrontDecoder(r.payload, r.header, protocol::kDefaultMaxResumeLeaves);
    return;
  }
  tags_ = std::move(r.tags);
  resume_.reset();
  park_if_due();
  queue_base();
}

// BASE, and CODEC when the session's packets are split records (protocol::carries_split_records): not
// the plain option.
void SenderDrivenMode::queue_base() {
  const PhaseTimer timer(context_.phases, Phase::send_base);
  context_.outbox.push_back(context_.served.base_frame);
  if (!plain_) context_.outbox.push_back(context_.served.tables->records().codec_frame);
}

// A VIEW's answer: splits accumulate across slices into batches of batch_splits. Splits of an earlier
// VIEW still in the batch go out with the new one's frame number (the client applies every batch).
void SenderDrivenMode::pump_answer(uint64_t& work) {
  unpark();
  if (ahead_streamer_.active()) {  // the VIEW goes first; the ahead answer starts again after it
    ahead_streamer_.stop();
    ahead_.restart = true;
  }
  if (std::exchange(view_.restart, false))
    streamer_.start(context_.served.model(), context_.served.tables->selective().dependencies, tags_, importance_,
                    context_.phases);
  const size_t limit = context_.limits.batch_splits;
  const size_t room = batch_.size() < limit ? limit - batch_.size() : 0;
  const bool served = streamer_.step(room, context_.limits.slice_work, batch_, work, plain_ ? &batch_cuts_ : nullptr);
  while (batch_.size() > limit || (batch_.size() == limit && !served)) emit_batch(limit, false);
  if (served) {
    streamer_.stop();
    view_.pending = false;
    emit_batch(batch_.size(), true);
    park_if_due();
  }
}

// Idle: no VIEW to answer, nothing waiting to be sent (the pipe's next bytes would be the next VIEW's
// answer), and budget left.
bool SenderDrivenMode::ahead_due() const {
  return ahead_.pending && !resume_ && !view_.pending && context_.outbox.empty() &&
         ahead_bytes_ < context_.limits.ahead_budget_bytes;
}

// One small batch at a time, each only once the one before has left the outbox: a VIEW that comes meanwhile
// waits behind at most one batch.
void SenderDrivenMode::pump_ahead(uint64_t& work) {
  unpark();
  if (std::exchange(ahead_.restart, false))
    ahead_streamer_.start(context_.served.model(), context_.served.tables->selective().dependencies, tags_,
                          ahead_importance_);
  const bool served = ahead_streamer_.step(kAheadBatchSplits, context_.limits.slice_work, ahead_batch_, work);
  // A dependency chain can carry the batch past batch_splits: it leaves in messages of at most that many.
  const size_t per_message = std::max<size_t>(1, context_.limits.batch_splits);
  for (size_t at = 0; at < ahead_batch_.size(); at += per_message) {
    const auto nodes = std::span(ahead_batch_).subspan(at, std::min(per_message, ahead_batch_.size() - at));
    std::vector<uint8_t> frame = context_.served.tables->packets().encode_ahead(ahead_.frame, nodes);
    ahead_bytes_ += frame.size();
    splits_sent_ += nodes.size();
    context_.queue(std::move(frame));
  }
  ahead_batch_.clear();
  if (served || ahead_bytes_ >= context_.limits.ahead_budget_bytes) {
    stop_ahead();
    park_if_due();
  }
}

void SenderDrivenMode::stop_ahead() {
  ahead_streamer_.stop();
  ahead_.pending = false;
}

bool SenderDrivenMode::can_park() const {
  return context_.limits.compact_fronts && parked_.empty() && !resume_ && !view_.pending && !ahead_streamer_.active();
}

void SenderDrivenMode::park_front() {
  if (!can_park()) return;
  const PhaseTimer timer(context_.phases, Phase::update_front);
  parked_ = CompactFront(context_.served.model(), tags_);
  tags_ = ActiveTags();
}

void SenderDrivenMode::park_if_due() {
  if (context_.limits.park_after_ms == 0) park_front();
}

void SenderDrivenMode::unpark() {
  if (parked_.empty()) return;
  const PhaseTimer timer(context_.phases, Phase::update_front);
  tags_ = parked_.tags(context_.served.model());
  parked_ = CompactFront();
}

ActiveTags SenderDrivenMode::front_tags() const {
  return parked_.empty() ? tags_ : parked_.tags(context_.served.model());
}

// The first `count` splits of the batch (a VSPLITS never holds more than batch_splits: a dependency chain
// can carry the batch past it, and the rest waits for the next frame, in order).
void SenderDrivenMode::emit_batch(size_t count, bool final) {
  const PhaseTimer timer(context_.phases, Phase::search_splits);
  const std::span<const uint32_t> nodes = std::span(batch_).first(count);
  if (plain_) {
    context_.queue(encode_plain_batch(context_.served.model(), plain_wire_, view_.frame, final, nodes,
                                      std::span(batch_cuts_).first(count)));
    batch_cuts_.erase(batch_cuts_.begin(), batch_cuts_.begin() + ptrdiff_t(count));
  } else {
    context_.queue(context_.served.tables->packets().encode(view_.frame, final, nodes));
  }
  splits_sent_ += count;
  batch_.erase(batch_.begin(), batch_.begin() + ptrdiff_t(count));
}

size_t SenderDrivenMode::state_bytes() const {
  size_t bytes = sizeof(*this) + front_bytes() + streamer_.memory_bytes() + ahead_streamer_.memory_bytes() +
                 ahead_batch_.capacity() * sizeof(uint32_t) +
                 batch_.capacity() * sizeof(uint32_t) + batch_cuts_.capacity() * sizeof(ActualCuts);
  if (resume_)
    bytes += sizeof(Resume) + resume_->payload.capacity() + resume_->tags.memory_bytes() +
             resume_->leaves.capacity() * sizeof(VertexId);
  return bytes;
}

}  // namespace pms::server
