// The DAG mode: MANAGE-TRAVERSAL on the session's cut, its operations as DAG_OPS.
#include "server/dag_mode.h"

#include <algorithm>
#include <string>
#include <utility>
#include <variant>

#include "common/error.h"
#include "dag/cut.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "spm/hierarchy.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::server {

using protocol::ErrorCode;
using protocol::ProtocolError;

// The vertices of the client's mesh are a complete front of the forest, and the split nodes of its cut are
// the front's inner nodes: each is found once, from the last leaf of its subtree in preorder (the climb
// through v_u children), so a slice of leaves costs at most 63 steps each.
struct DagSessionMode::Resume {
  Resume(std::vector<uint8_t> front, const protocol::OpenHeader& h)
      : payload(std::move(front)), header(h), decoder(payload, header, protocol::kDefaultMaxResumeLeaves) {}

  std::vector<uint8_t> payload;
  protocol::OpenHeader header;
  protocol::FrontDecoder decoder;
  std::vector<VertexId> leaves;  // one slice's
  std::vector<uint32_t> split;   // DAG nodes
};

DagSessionMode::DagSessionMode(const protocol::OpenHeader& open, protocol::Frame& open_frame,
                               const ModeContext& context)
    : context_(context), wire_(context.served.context) {
  wire_.has_refinement = false;
  if (!open.resume) {
    context_.outbox.push_back(context_.served.base_frame);
    return;
  }
  const uint32_t roots = context_.served.model().root_count;
  if (open.resume_trees != roots)
    throw ProtocolError(ErrorCode::bad_id, "OPEN: resume: the front covers " + std::to_string(open.resume_trees) +
                                               " trees, the model has " + std::to_string(roots));
  resume_ = std::make_unique<Resume>(std::move(open_frame.payload), open);
}

DagSessionMode::~DagSessionMode() = default;

void DagSessionMode::pump_resume(uint64_t& work) {
  Resume& r = *resume_;
  const ModelData& model = context_.served.model();
  const Dag& dag = context_.served.tables->dag();
  r.leaves.clear();
  const bool decoded = r.decoder.next(context_.limits.slice_work, r.leaves);
  work += r.leaves.size();
  for (const VertexId& id : r.leaves) {
    const uint32_t node = model.find(id);
    if (node == kNone)
      throw ProtocolError(ErrorCode::bad_id, "OPEN: resume id " + to_string(id) + " is not in the model");
    append_closed_splits(model, dag, node, r.split);
  }
  if (!decoded) return;
  try {
    LoadedDagCut loaded(dag, r.split);  // one turn, O(split nodes): as bounded as a traversal of that cut
    work += r.split.size();
    cut_ = loaded.store();
  } catch (const Error& e) {
    throw ProtocolError(ErrorCode::bad_id,
                        std::string("OPEN: resume: the mesh is not a cut of the model's DAG (") + e.what() + ")");
  }
  answered_ = cut_.split_count() > 0;  // the client has a picture: N applies from its first DAG_VIEW
  resume_.reset();
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
  if (resume_) return pump_resume(work);
  if (sent_ < ops_.size() || answering_) return emit_batch(work);
  if (pending_) traverse(work);
}

void DagSessionMode::stop() {
  resume_.reset();
  pending_ = answering_ = false;
  std::vector<DagOp>().swap(ops_);
  sent_ = 0;
}

void DagSessionMode::traverse(uint64_t& work) {
  pending_ = false;
  LoadedDagCut loaded(context_.served.tables->dag(), cut_);  // O(split nodes × degree) each way
  DagTraverser traverser(loaded.cut());
  traverser.set_view(view_.criteria);
  ops_.clear();
  // The first picture is the converged mesh of the first view: N amortizes a view change over frames, and
  // before its first answer the client has no picture whose frame rate N would keep (docs/internals.md,
  // "The DAG mode"). It is bounded as any view is: at most the largest N a client may ask for.
  const DagFrameStats stats =
      answered_ ? traverser.manage(options_, ops_) : traverser.converge(options_, ops_, protocol::kMaxDagOps);
  cut_ = loaded.store();
  answered_ = true;
  work += stats.evaluated + ops_.size() + cut_.split_count();
  sent_ = 0;
  answer_frame_ = view_.frame;
  answering_ = true;
}

// The next batch_splits operations of the answer; the last batch (possibly empty) is final.
void DagSessionMode::emit_batch(uint64_t& work) {
  const ModelData& model = context_.served.model();
  const Dag& dag = context_.served.tables->dag();
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
  size_t bytes = sizeof(*this) + cut_.memory_bytes() + ops_.capacity() * sizeof(DagOp);
  if (resume_)
    bytes += sizeof(Resume) + resume_->payload.capacity() + resume_->leaves.capacity() * sizeof(VertexId) +
             resume_->split.capacity() * sizeof(uint32_t);
  return bytes;
}

}  // namespace pms::server
