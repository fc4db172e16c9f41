#include "bench/split_record_bits.h"

#include "apps/camera_path.h"
#include "common/bit_stream.h"
#include "protocol/model_messages.h"
#include "protocol/packet_bits.h"
#include "spm/adapt.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"

namespace pms::bench {
using app::make_camera_path;
using app::PathKind;
using app::PathOptions;

RecordBitsReport record_bits(const ModelData& model, const SplitCodec& codec, std::span<const uint32_t> positions,
                             std::span<const uint32_t> nodes) {
  RecordBitsReport report;
  BitWriter tables;
  codec.serialize(tables);
  report.table_bits = tables.size();
  const protocol::StreamContext context =
      protocol::stream_context(protocol::make_base(model, "model", codec.position_bits()));
  for (uint32_t node : nodes) {
    BitWriter w;
    RecordBits bits;
    codec.encode(split_context(model, positions, node), split_payload(model, positions, node), w, &bits);
    report.bits += bits;
    report.packet_refinement += protocol::packet_bits(split_record(model, node), context).refinement;
    ++report.splits;
  }
  return report;
}

Camera close_view(const ModelData& model) {
  PathOptions options;
  options.frames = 1;
  Camera c = make_camera_path(PathKind::orbit, model, options)[0];
  for (int k = 0; k < 3; ++k) c.eye[k] = 0.5f * (c.eye[k] + c.target[k]);
  return c;
}

std::vector<uint32_t> splits_for_view(const ModelData& model, const Camera& camera, float tolerance_px) {
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  AdaptOptions options;
  options.tolerance = tolerance_px;
  SelectiveRefinement refinement(mesh, model.scale, options);
  refinement.set_view(make_view(camera, model.bbox_min, model.bbox_max));
  refinement.converge([&](std::span<const uint32_t> leaves) { return add_model_splits(hierarchy, model, leaves); });
  std::vector<uint32_t> nodes;
  for (uint32_t slot = 0; slot < hierarchy.size(); ++slot)
    if (!hierarchy.is_leaf(slot)) nodes.push_back(model.find(hierarchy.id(slot)));
  return nodes;
}

}  // namespace pms::bench
