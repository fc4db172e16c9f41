// The DAG mode (zheng-chan 2006 §4–5, StreamMode::dag): a thin client with no hierarchy walk and no criteria
// of its own, driven by the server. The session holds the client's cut of the model's DAG of operations
// (dag/cut.h, about a byte per node) and a traverser; each DAG_VIEW runs MANAGE-TRAVERSAL once on it
// (the first one: the converged cut of its view) and the operations go down as DAG_OPS in batches, collapses
// first, then splits with their geometry and fundamental cut vertices (docs/internals.md, "The DAG mode": why
// not the actual ones), so the client's mesh is the server's cut after every answer. An OPEN with a resume
// front lists the client's mesh (dag/cut.h, cut_front), rebuilt here into the cut a slice at a time.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "dag/compact.h"
#include "dag/traversal.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/stream_context.h"
#include "server/session_mode.h"

namespace pms::server {

class DagSessionMode : public SessionMode {
 public:
  // Queues BASE at once for a fresh session; a resumed one decodes its front first (pump()). ProtocolError
  // for a front over another number of trees.
  DagSessionMode(const protocol::OpenHeader& open, protocol::Frame& open_frame, const ModeContext& context);
  ~DagSessionMode() override;

  void receive(const protocol::ClientMessage& message) override;
  bool has_work() const override { return resume_ || pending_ || sent_ < ops_.size() || answering_; }
  // Either one MANAGE-TRAVERSAL for the latest DAG_VIEW or one DAG_OPS batch of its answer (docs/internals.md,
  // "The DAG mode": why one traversal is a bounded slice).
  void pump(uint64_t& work) override;
  bool opened() const override { return !resume_; }
  void stop() override;
  size_t state_bytes() const override;
  size_t front_bytes() const override { return cut_.memory_bytes(); }
  uint64_t splits_sent() const override { return splits_sent_; }

  // For tests and fuzzers: the client's mesh is this cut's (CompactDagCut::dense for a DagCut).
  const CompactDagCut& cut() const { return cut_; }

 private:
  struct Resume;  // an OPEN's resume front, decoded a slice at a time into the cut's split nodes
  void pump_resume(uint64_t& work);
  void traverse(uint64_t& work);
  void emit_batch(uint64_t& work);

  ModeContext context_;
  protocol::StreamContext wire_;  // no refinement info: the client has no criteria
  std::unique_ptr<Resume> resume_;
  CompactDagCut cut_;  // between turns: the dense cut is the I/O thread's (LoadedDagCut)
  LatestView view_;
  DagManageOptions options_;
  bool pending_ = false;    // a DAG_VIEW waits for its traversal
  bool answering_ = false;  // the final DAG_OPS of the traversed view is still to send
  bool answered_ = false;   // a view was traversed: the next ones are N-limited
  uint32_t answer_frame_ = 0;
  std::vector<DagOp> ops_;  // the answer: collapses, then splits
  size_t sent_ = 0;
  uint64_t splits_sent_ = 0;
};

}  // namespace pms::server
