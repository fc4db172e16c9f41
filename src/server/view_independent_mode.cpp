// The view-independent mode (kim-lee-kobbelt §8, Fig. 9): the PM order's prefix a view needs, in slices.
#include "server/view_independent_mode.h"

#include <algorithm>
#include <utility>
#include <variant>
#include <vector>

#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "spm/hierarchy.h"
#include "spm/split_record.h"

namespace pms::server {

using protocol::ErrorCode;
using protocol::ProtocolError;

// The shortest prefix of split_order whose front satisfies the view. SelectiveStreaming on a copy of the
// tags (the front of the prefix sent) collects every split the view wants there, partial-order
// dependencies included; the furthest of them in PM order ends the prefix. The PM order makes other
// splits on the way, whose children the view may want in turn, so the walk repeats from the new prefix's
// front until it wants nothing (each round only moves the end right).
struct ViewIndependentMode::Prefix {
  enum class Phase { walking, advancing, streaming };
  Phase phase = Phase::walking;
  ActiveTags front;  // the front of split_order[0, end) plus what the walk split
  SelectiveStreamer walk;
  std::vector<uint32_t> wanted;  // one slice's
  bool wanted_any = false;
  uint64_t end = 0, furthest = 0, next = 0;
};

ViewIndependentMode::ViewIndependentMode(const protocol::OpenHeader& open, const ModeContext& context)
    : context_(context),
      wire_(context.served.context),
      importance_(view_.importance(context.served.tables->selective().criteria)) {
  if (open.resume)
    throw ProtocolError(ErrorCode::bad_message,
                        "OPEN: resume: a view-independent session cannot resume (sender-driven only)");
  wire_.has_refinement = false;
  tags_ = ActiveTags(context_.served.model().root_count);
  context_.outbox.push_back(context_.served.base_frame);
}

ViewIndependentMode::~ViewIndependentMode() = default;

void ViewIndependentMode::receive(const protocol::ClientMessage& message) {
  const auto* view = std::get_if<protocol::View>(&message);
  if (!view) throw ProtocolError(ErrorCode::out_of_order, "a view-independent session takes only VIEW after OPEN");
  view_.record(*view, context_.served.model());
}

void ViewIndependentMode::stop() {
  prefix_.reset();
  view_.pending = false;
}

void ViewIndependentMode::pump(uint64_t& work) {
  if (!view_.pending) return;
  if (std::exchange(view_.restart, false)) {
    if (!prefix_) prefix_ = std::make_unique<Prefix>();
    Prefix& p = *prefix_;
    p.phase = Prefix::Phase::walking;
    p.front = tags_;
    p.end = sent_;
    p.wanted_any = false;
    p.walk.start(context_.served.model(), context_.served.tables->selective().dependencies, p.front, importance_);
  }
  Prefix& p = *prefix_;
  switch (p.phase) {
    case Prefix::Phase::walking:
      return walk(p, work);
    case Prefix::Phase::advancing:
      return advance(p, work);
    case Prefix::Phase::streaming:
      return stream(p, work);
  }
}

// What the view wants over the prefix's front; the furthest of it in PM order ends the prefix.
void ViewIndependentMode::walk(Prefix& p, uint64_t& work) {
  p.wanted.clear();
  const bool served = p.walk.step(SIZE_MAX, context_.limits.slice_work, p.wanted, work);
  if (!p.wanted.empty() && !p.wanted_any) {
    p.wanted_any = true;
    p.furthest = p.end;
  }
  for (uint32_t node : p.wanted)
    p.furthest = std::max<uint64_t>(p.furthest, uint64_t(context_.served.tables->split_rank()[node]) + 1);
  if (!served) return;
  p.walk.stop();
  p.phase = p.wanted_any ? Prefix::Phase::advancing : Prefix::Phase::streaming;
  p.next = p.end;
}

// The rest of the prefix, so `front` is again the front of split_order[0, furthest); then walk again.
void ViewIndependentMode::advance(Prefix& p, uint64_t& work) {
  const ModelData& model = context_.served.model();
  const uint64_t begin = p.next, stop = std::min<uint64_t>(p.furthest, p.next + context_.limits.slice_work);
  for (; p.next < stop; ++p.next) {
    const uint32_t node = model.split_order[p.next];
    if (p.front.is_active(node)) p.front.split(node, model.first_child[node]);  // else split above, as wanted
  }
  work += stop - begin;
  if (p.next < p.furthest) return;
  p.end = p.furthest;
  p.wanted_any = false;
  p.phase = Prefix::Phase::walking;
  p.walk.start(model, context_.served.tables->selective().dependencies, p.front, importance_);
}

// split_order[sent_, end) in PM order; the last (possibly empty) batch is final.
void ViewIndependentMode::stream(Prefix& p, uint64_t& work) {
  const ModelData& model = context_.served.model();
  const uint64_t stop =
      std::min<uint64_t>({p.end, sent_ + context_.limits.batch_splits, sent_ + context_.limits.slice_work});
  protocol::VSplits message;
  message.frame = view_.frame;
  message.final = stop >= p.end;
  message.splits.reserve(size_t(stop - sent_));
  for (; sent_ < stop; ++sent_) {
    const uint32_t node = model.split_order[sent_];
    tags_.split(node, model.first_child[node]);
    message.splits.push_back(split_record(model, node));
  }
  work += message.splits.size();
  context_.queue(protocol::encode(message, wire_));
  if (message.final) {
    view_.pending = false;
    prefix_.reset();  // its copy of the tags is only needed while a VIEW is answered
  }
}

size_t ViewIndependentMode::state_bytes() const {
  size_t bytes = sizeof(*this) + tags_.memory_bytes();
  if (prefix_)
    bytes += sizeof(Prefix) + prefix_->front.memory_bytes() + prefix_->walk.memory_bytes() +
             prefix_->wanted.capacity() * sizeof(uint32_t);
  return bytes;
}

}  // namespace pms::server
