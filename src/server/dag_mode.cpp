// The DAG mode: MANAGE-TRAVERSAL on the session's cut, its operations as DAG_OPS with the client's cut vertices.
#include "server/dag_mode.h"

#include <algorithm>
#include <variant>

#include "common/error.h"
#include "pm/hierarchy.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "server/plain_packets.h"

namespace pms::server {

using protocol::ErrorCode;
using protocol::ProtocolError;

DagSessionMode::DagSessionMode(const protocol::OpenHeader& open, const ModeContext& context)
    : context_(context), wire_(context.served.context), cut_(*context.served.dag), traverser_(cut_) {
  if (open.resume) throw ProtocolError(ErrorCode::bad_message, "OPEN: the DAG mode does not resume a session");
  wire_.has_refinement = false;
  context_.outbox.push_back(context_.served.base_frame);
}

// Only the latest DAG_VIEW counts: one not yet traversed is replaced, an answer being sent is finished first
// (the client applies every operation of it).
void DagSessionMode::receive(const protocol::ClientMessage& message) {
  const auto* request = std::get_if<protocol::DagView>(&message);
  if (!request) throw ProtocolError(ErrorCode::out_of_order, "a DAG session takes only DAG_VIEW after OPEN");
  view_.record(request->view, context_.served.model());
  options_ = {request->traversal, request->management, request->max_ops, request->budget};
  pending_ = true;
}

void DagSessionMode::pump(uint64_t& work) {
  if (sent_ < ops_.size() || answering_) return emit_batch(work);
  if (pending_) traverse(work);
}

void DagSessionMode::stop() {
  pending_ = answering_ = false;
  ops_ = {};
  cuts_ = {};
  split_at_ = {};
  sent_ = cuts_sent_ = 0;
}

void DagSessionMode::traverse(uint64_t& work) {
  pending_ = false;
  traverser_.set_view(view_.criteria);
  ops_.clear();
  const DagFrameStats stats = traverser_.manage(options_, ops_);
  work += stats.evaluated + ops_.size();
  record_cuts();
  sent_ = cuts_sent_ = 0;
  answer_frame_ = view_.frame;
  answering_ = true;
}

// The cut vertices each split has on the client's mesh when it comes: the active ancestors of its
// fundamental ones on the cut as it stands after the collapses and the splits before it.
void DagSessionMode::record_cuts() {
  split_at_.clear();
  for (uint32_t i = 0; i < ops_.size(); ++i)
    if (ops_[i].split) split_at_.emplace_back(ops_[i].node, i);
  std::sort(split_at_.begin(), split_at_.end());
  const ModelData& model = context_.served.model();
  const Dag& dag = *context_.served.dag;
  cuts_.clear();
  for (uint32_t i = 0; i < ops_.size(); ++i) {
    if (!ops_[i].split) continue;
    const uint32_t v = dag.model_node(ops_[i].node);
    cuts_.push_back({actual_cut(model.cut_left[v], i), actual_cut(model.cut_right[v], i)});
  }
}

// Whether `model_node` is split when operation `op` is made (the cut holds the answer's end state).
bool DagSessionMode::split_before(uint32_t model_node, uint32_t op) const {
  const uint32_t n = context_.served.dag->node_of(model_node);
  if (n == kNone || !cut_.is_split(n)) return false;
  const auto at = std::lower_bound(split_at_.begin(), split_at_.end(), std::make_pair(n, uint32_t(0)));
  // Split by this answer: only once its own split has been made (a node is split at most once per answer).
  return at == split_at_.end() || at->first != n || at->second < op;
}

uint32_t DagSessionMode::actual_cut(uint32_t fundamental, uint32_t op) const {
  if (fundamental == kNone) return kNone;
  const ModelData& model = context_.served.model();
  if (split_before(fundamental, op)) fail("DAG mode", "a fundamental cut vertex is split below the cut");
  uint32_t a = fundamental;
  for (uint32_t p = model.parent[a]; p != kNone && !split_before(p, op); p = model.parent[a]) a = p;
  return a;
}

// The next batch_splits operations of the answer; the last batch (possibly empty) is final.
void DagSessionMode::emit_batch(uint64_t& work) {
  const ModelData& model = context_.served.model();
  const Dag& dag = *context_.served.dag;
  const size_t end = std::min(ops_.size(), sent_ + context_.limits.batch_splits);
  protocol::DagOps message;
  message.frame = answer_frame_;
  for (; sent_ < end; ++sent_) {
    const DagOp& op = ops_[sent_];
    const uint32_t v = dag.model_node(op.node);
    if (!op.split) {
      message.collapses.push_back(model.id(v));
      continue;
    }
    message.splits.push_back(plain_split(model, v, cuts_[cuts_sent_++]));
  }
  message.final = sent_ == ops_.size();
  work += message.collapses.size() + message.splits.size();
  splits_sent_ += message.splits.size();
  context_.queue(protocol::encode(message, wire_));
  if (message.final) {
    answering_ = false;
    ops_.clear();
    cuts_.clear();
    split_at_.clear();
  }
}

size_t DagSessionMode::state_bytes() const {
  return sizeof(*this) + cut_.memory_bytes() + traverser_.memory_bytes() + ops_.capacity() * sizeof(DagOp) +
         cuts_.capacity() * sizeof(ActualCuts) + split_at_.capacity() * sizeof(split_at_[0]);
}

}  // namespace pms::server
