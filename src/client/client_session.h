// A streaming client's protocol logic without I/O (kim-lee-kobbelt 2005 §5.3): it keeps the partial vertex
// hierarchy and the selectively refined mesh built from what the server sent.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "common/camera.h"
#include "protocol/client_messages.h"
#include "protocol/server_messages.h"
#include "protocol/split_request.h"
#include "protocol/stream_context.h"
#include "spm/adapt.h"
#include "spm/selective_mesh.h"
#include "spm/split_codec.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::client {

class ClientSession {
 public:
  // Builds the base mesh, hierarchy and refinement loop from a BASE. With `keep` (a resumed session whose
  // hierarchy is already here) the BASE only has to match the model held.
  void on_base(const protocol::Base& base);
  // The split record tables of a session whose packets are split records (protocol::carries_split_records),
  // after BASE: from now on VSPLITS decode against this hierarchy. A resumed session's must be the ones held.
  void on_codec(const protocol::Codec& codec);
  // Attaches a batch's packets as leaves of the partial hierarchy (UpdateVHierarchy). Applying them to
  // the mesh is the mode's business (client_mode.h).
  void on_vsplits(const protocol::VSplits& batch);
  // The same for a receiver-driven answer in records format 3 (protocol/split_bands.h): the bands of
  // `request`'s ids, coded with `codec`. Returns the splits attached.
  uint32_t on_split_bands(std::span<const uint8_t> body, const protocol::SplitRequest& request,
                          const SplitCodec& codec);
  // Makes every split of an attached batch on the mesh, in order: for the modes whose client applies
  // splits as they arrive. pms::Error naming `promise` (the order the server owes) when one cannot be made.
  void apply_as_they_come(const protocol::VSplits& batch, const char* promise);
  // The DAG mode's operations, in order: collapses, then splits (attached first if not yet known). pms::Error
  // when one cannot be made on this mesh. Returns the splits made.
  size_t apply_dag_ops(const protocol::DagOps& ops);

  bool has_model() const { return refinement_ != nullptr; }
  const protocol::StreamContext& context() const { return context_; }
  const protocol::Base& base() const { return base_; }
  VertexHierarchy& hierarchy() { return *hierarchy_; }
  SelectiveMesh& mesh() { return *mesh_; }
  const SelectiveMesh& mesh() const { return *mesh_; }
  SelectiveRefinement& refinement() { return *refinement_; }
  const SelectiveRefinement& refinement() const { return *refinement_; }
  ViewParams view_params(const Camera& camera) const;
  // The leaves of the partial hierarchy: what a resumed session sends in OPEN.
  std::vector<VertexId> known_leaves() const;
  // The ids of the mesh's vertices: a complete front too (what a DAG session resumes from).
  std::vector<VertexId> mesh_vertices() const;
  uint64_t splits_received() const { return splits_received_; }

  AdaptOptions adapt_options;
  // New adapt options now, for the refinement held too (the mesh is kept; the next adapt uses them).
  void set_adapt_options(const AdaptOptions& options);
  // Set before on_base, by the mode: whether its packets carry refinement info.
  bool refinement_info = true;

 private:
  protocol::Base base_;
  protocol::StreamContext context_;
  std::vector<uint8_t> codec_tables_;  // the CODEC held, to check a resumed session's against
  std::unique_ptr<VertexHierarchy> hierarchy_;
  std::unique_ptr<SelectiveMesh> mesh_;
  std::unique_ptr<SelectiveRefinement> refinement_;
  uint64_t splits_received_ = 0;
};

}  // namespace pms::client
