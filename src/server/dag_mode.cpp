// The DAG mode: MANAGE-TRAVERSAL on the session's cut, its operations as DAG_OPS.
#include "server/dag_mode.h"

#include <algorithm>
#include <variant>

#include "common/error.h"
#include "pm/hierarchy.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "pm/split_record.h"

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
  std::vector<DagOp>().swap(ops_);
  sent_ = 0;
}

void DagSessionMode::traverse(uint64_t& work) {
  pending_ = false;
  traverser_.set_view(view_.criteria);
  ops_.clear();
  // The first picture is the converged mesh of the first view: N amortizes a view change over frames, and
  // before its first answer the client has no picture whose frame rate N would keep (docs/internals.md,
  // "The DAG mode"). It is bounded as any view is: at most the largest N a client may ask for.
  const DagFrameStats stats =
      answered_ ? traverser_.manage(options_, ops_) : traverser_.converge(options_, ops_, protocol::kMaxDagOps);
  answered_ = true;
  work += stats.evaluated + ops_.size();
  sent_ = 0;
  answer_frame_ = view_.frame;
  answering_ = true;
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
    message.splits.push_back(split_record(model, v));
  }
  message.final = sent_ == ops_.size();
  work += message.collapses.size() + message.splits.size();
  splits_sent_ += message.splits.size();
  context_.queue(protocol::encode(message, wire_));
  if (message.final) {
    answering_ = false;
    std::vector<DagOp>().swap(ops_);  // a first answer is the whole converged cut: do not keep its capacity
  }
}

size_t DagSessionMode::state_bytes() const {
  return sizeof(*this) + cut_.memory_bytes() + ops_.capacity() * sizeof(DagOp);
}

}  // namespace pms::server
