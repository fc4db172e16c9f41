// One client's session of the sender-driven protocol (kim-lee-kobbelt §5.3): HELLO, LIST, OPEN (with
// resume), VIEW -> SelectiveStreaming in batches, CLOSE. The session holds a reference to its model
// and the windowed active tags; a VIEW's ranking lives only while that VIEW is being answered.
// A view-independent session (the baseline of §8, Fig. 9) streams the plain PM order instead: each VIEW
// extends the prefix of split_order sent up to the shortest one that satisfies the view.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <variant>

#include "server/server.h"

namespace pms::server {
namespace {

using protocol::ErrorCode;
using protocol::ProtocolError;

}  // namespace

Session::Session(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits)
    : catalogue_(std::move(catalogue)), limits_(limits) {}

void Session::queue(std::vector<uint8_t> frame) {
  outbox_.push_back(std::make_shared<const std::vector<uint8_t>>(std::move(frame)));
}

void Session::abort_with(ErrorCode code, const std::string& text) {
  if (closing_) return;
  streamer_.stop();
  queue(protocol::encode(protocol::ErrorMessage{code, text}));
  closing_ = true;
}

void Session::receive(const protocol::Frame& frame) {
  if (closing_) return;
  try {
    const protocol::ClientMessage message = protocol::decode_client_message(frame);
    if (!greeted_ && !std::holds_alternative<protocol::Hello>(message))
      throw ProtocolError(ErrorCode::out_of_order, protocol::to_string(frame.type) + " before HELLO");
    if (const auto* hello = std::get_if<protocol::Hello>(&message)) {
      on_hello(*hello);
    } else if (std::holds_alternative<protocol::List>(message)) {
      queue(catalogue_->catalogue_frame());
    } else if (const auto* open = std::get_if<protocol::Open>(&message)) {
      on_open(*open);
    } else if (const auto* view = std::get_if<protocol::View>(&message)) {
      on_view(*view);
    } else {  // CLOSE
      streamer_.stop();
      closing_ = true;
    }
  } catch (const ProtocolError& e) {
    abort_with(e.code, e.what());
  } catch (const Error& e) {
    abort_with(ErrorCode::bad_message, e.what());
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

void Session::on_open(const protocol::Open& m) {
  if (model_) throw ProtocolError(ErrorCode::out_of_order, "OPEN: a model is already open in this session");
  const ServedModel* model = catalogue_->find(m.model);
  if (!model) throw ProtocolError(ErrorCode::unknown_model, "OPEN: no model named '" + m.model + "'");
  if (m.mode == protocol::StreamMode::view_independent && !m.resume.empty())
    throw ProtocolError(ErrorCode::bad_message,
                        "OPEN: resume: a view-independent session cannot resume (sender-driven only)");
  const ModelView& view = model->view();
  ActiveTags tags(m.resume.empty() ? view.root_count : 0);
  // Resume (kim-lee-kobbelt §5.3 "Session close"): the client's known leaves are the front.
  for (const VertexId& id : m.resume) {
    if (id.tree >= view.root_count)
      throw ProtocolError(ErrorCode::bad_id, "OPEN: resume id " + to_string(id) + " has no tree in the model");
    const uint32_t node = view.find(id);
    if (node == kNone) throw ProtocolError(ErrorCode::bad_id, "OPEN: resume id " + to_string(id) + " not in the model");
    tags.activate(node);
  }
  model_ = model;
  mode_ = m.mode;
  context_ = model->context;
  context_.has_refinement = mode_ == protocol::StreamMode::sender_driven;
  tags_ = std::move(tags);
  outbox_.push_back(model->base_frame);
}

void Session::on_view(const protocol::View& m) {
  if (!model_) throw ProtocolError(ErrorCode::out_of_order, "VIEW before OPEN");
  const ModelView& model = model_->view();
  // The same derivation as the client's, from the same box: bit-identical criteria on both ends.
  view_ = make_criteria(make_view(m.camera, model.bbox_min, model.bbox_max), m.tolerance);
  view_frame_ = m.frame;
  if (mode_ == protocol::StreamMode::view_independent) {
    prefix_end_ = prefix_for_view();
    answering_prefix_ = true;
    return;
  }
  // A new VIEW replaces the one being answered: what was not sent yet is judged again under the new one.
  const std::vector<NodeCriteria>& criteria = model_->criteria;
  streamer_.start(model, model_->dependencies, tags_,
                  [this, &criteria](uint32_t node) { return refinement_priority(view_, criteria[node]); });
}

// The shortest prefix of split_order whose front satisfies the view. SelectiveStreaming on a copy of the
// tags (the front of the prefix sent) collects every split the view wants there, partial-order
// dependencies included; the furthest of them in PM order ends the prefix. The PM order makes other
// splits on the way, whose children the view may want in turn, so the walk repeats from the new
// prefix's front until it wants nothing (each round only moves the end right).
uint64_t Session::prefix_for_view() const {
  const ModelView& model = model_->view();
  const std::vector<NodeCriteria>& criteria = model_->criteria;
  const ViewCriteria& view = view_;
  const Importance importance = [&](uint32_t node) { return refinement_priority(view, criteria[node]); };
  ActiveTags front = tags_;
  uint64_t end = sent_;
  std::vector<uint32_t> wanted;
  for (;;) {
    wanted.clear();
    selective_streaming(model, model_->dependencies, front, importance, SIZE_MAX, wanted);
    if (wanted.empty()) return end;
    uint64_t furthest = end;
    for (uint32_t node : wanted) furthest = std::max<uint64_t>(furthest, uint64_t(model_->split_rank[node]) + 1);
    // The rest of the prefix, so `front` is again the front of split_order[0, furthest).
    for (uint64_t i = end; i < furthest; ++i) {
      const uint32_t node = model.split_order[i];
      if (!front.is_active(node)) continue;  // split above as one the view wanted
      front.deactivate(node);
      front.activate(model.first_child[node]);
      front.activate(model.first_child[node] + 1);
    }
    end = furthest;
  }
}

// The next batch of split_order[sent_, prefix_end_); the last (possibly empty) one is final.
bool Session::pump_view_independent() {
  if (!answering_prefix_) return false;
  const ModelView& model = model_->view();
  const uint64_t stop = std::min<uint64_t>(prefix_end_, sent_ + limits_.batch_splits);
  protocol::VSplits message;
  message.frame = view_frame_;
  message.final = stop >= prefix_end_;
  for (; sent_ < stop; ++sent_) {
    const uint32_t node = model.split_order[sent_];
    tags_.deactivate(node);
    tags_.activate(model.first_child[node]);
    tags_.activate(model.first_child[node] + 1);
    message.splits.push_back(split_record(model, node));
  }
  queue(protocol::encode(message, context_));
  splits_sent_ += message.splits.size();
  if (message.final) answering_prefix_ = false;
  return true;
}

bool Session::pump() {
  if (closing_) return false;
  if (mode_ == protocol::StreamMode::view_independent) return pump_view_independent();
  if (!streamer_.active()) return false;
  batch_.clear();
  const bool served = streamer_.step(limits_.batch_splits, batch_);
  queue(model_->packets.encode(view_frame_, served, batch_));
  splits_sent_ += batch_.size();
  if (served) streamer_.stop();
  return true;
}

size_t Session::state_bytes() const {
  return sizeof(*this) + tags_.memory_bytes() + streamer_.memory_bytes() + batch_.capacity() * sizeof(uint32_t);
}

}  // namespace pms::server
