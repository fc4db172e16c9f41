// The client's protocol logic (kim-lee-kobbelt §5.3): BASE builds the base mesh and the roots of the
// partial hierarchy; every VSPLITS packet is attached below its v_s (UpdateVHierarchy).

#include "client/client_session.h"

#include <algorithm>
#include <cstdint>

#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::client {

void ClientSession::set_adapt_options(const AdaptOptions& options) {
  if (refinement_) refinement_->set_options(options);
  adapt_options = options;
}

void ClientSession::on_base(const protocol::Base& base) {
  if (has_model()) {
    // A resumed session: the server sends BASE again; the hierarchy held must be of the same model (a file
    // replaced under the same name may keep the base mesh's size and faces: the positions tell it apart).
    if (base.root_count() != base_.root_count() || base.faces != base_.faces || base.scale != base_.scale ||
        base.positions != base_.positions)
      fail("BASE", "the server's model '" + base.model + "' is not the one this client holds");
    return;
  }
  base_ = base;
  context_ = protocol::stream_context(base);
  context_.has_refinement = refinement_info;
  hierarchy_ = std::make_unique<VertexHierarchy>(base.has_normals, base.has_colors);
  hierarchy_->reserve(base.root_count());
  for (uint32_t r = 0; r < base.root_count(); ++r)
    hierarchy_->add_root(VertexId{r, 1}, &base.positions[3 * size_t(r)], base.refine[r],
                         base.has_normals ? &base.normals[3 * size_t(r)] : nullptr,
                         base.has_colors ? &base.colors[4 * size_t(r)] : nullptr);
  mesh_ = std::make_unique<SelectiveMesh>(*hierarchy_, base.faces);
  refinement_ = std::make_unique<SelectiveRefinement>(*mesh_, base.scale, adapt_options);
}

void ClientSession::on_codec(const protocol::Codec& codec) {
  if (!has_model()) fail("CODEC", "received before BASE");
  if (context_.records) {
    if (codec.tables != codec_tables_)
      fail("CODEC", "the server's split record tables are not the ones this client holds");
    return;
  }
  codec_tables_ = codec.tables;
  context_.records = codec.codec;
  // What held_split_context reads is what the server's stored records are coded against (docs/protocol.md,
  // "Split records"); the hierarchy lives on the heap, so the reference outlives moves of this session.
  context_.held = protocol::held_in(*hierarchy_, context_.grid);
}

void ClientSession::on_vsplits(const protocol::VSplits& batch) {
  if (!has_model()) fail("VSPLITS", "received before BASE");
  for (const SplitRecord& split : batch.splits) hierarchy_->add_split(split);
  splits_received_ += batch.splits.size();
}

uint32_t ClientSession::on_split_bands(std::span<const uint8_t> body, const protocol::SplitRequest& request,
                                       const SplitCodec& codec) {
  if (!has_model()) fail("split records", "received before BASE");
  // A band holds at most every node of its depth + 1 levels.
  const uint64_t most = uint64_t(request.ids.size()) * ((uint64_t(2) << std::min<uint32_t>(request.depth, 30)) - 1);
  const uint32_t added = protocol::read_split_bands(body, request, codec, context_.grid, *hierarchy_,
                                                    uint32_t(std::min<uint64_t>(most, UINT32_MAX)));
  splits_received_ += added;
  return added;
}

void ClientSession::apply_as_they_come(const protocol::VSplits& batch, const char* promise) {
  for (const SplitRecord& split : batch.splits)
    if (!mesh_->vsplit(hierarchy_->find(split.vs)).done)
      fail("VSPLITS", "split of " + to_string(split.vs) + " cannot be made on this mesh yet (" + promise + ")");
}

size_t ClientSession::apply_dag_ops(const protocol::DagOps& ops) {
  if (!has_model()) fail("DAG_OPS", "received before BASE");
  for (VertexId v : ops.collapses) {
    const uint32_t slot = hierarchy_->find(v);
    if (slot == kNone || hierarchy_->is_leaf(slot) || !mesh_->ecol(slot))
      fail("DAG_OPS", "collapse of " + to_string(v) + " cannot be made on this mesh");
  }
  for (const SplitRecord& split : ops.splits) {
    uint32_t slot = hierarchy_->find(split.vs);
    if (slot == kNone || hierarchy_->is_leaf(slot)) {  // a node split before keeps its record
      hierarchy_->add_split(split);
      ++splits_received_;
      slot = hierarchy_->find(split.vs);
    }
    if (!mesh_->vsplit(slot).done) fail("DAG_OPS", "split of " + to_string(split.vs) + " cannot be made on this mesh");
  }
  return ops.splits.size();
}

ViewParams ClientSession::view_params(const Camera& camera) const {
  return make_view(camera, base_.bbox_min, base_.bbox_max);
}

std::vector<VertexId> ClientSession::known_leaves() const {
  std::vector<VertexId> leaves;
  for (uint32_t slot = 0; slot < hierarchy_->size(); ++slot)
    if (hierarchy_->is_leaf(slot)) leaves.push_back(hierarchy_->id(slot));
  return leaves;
}

std::vector<VertexId> ClientSession::mesh_vertices() const {
  std::vector<VertexId> ids;
  ids.reserve(mesh_->vertex_count());
  for (uint32_t slot : mesh_->active_vertices()) ids.push_back(hierarchy_->id(slot));
  return ids;
}

}  // namespace pms::client
