// A vertex split as every mode transmits and applies it.
#pragma once
#include <cstdint>

#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/vertex_id.h"

namespace pms {

// What a vsplit packet carries (kim-lee-kobbelt §5.3, Fig. 3b). v_u inherits v_s's position and
// attributes (half-edge collapse t -> u), so only v_t's geometry travels.
struct SplitRecord {
  VertexId vs;                 // the node being split
  VertexId cut_l = kNoVertex;  // fundamental cut vertices v̂_l, v̂_r (leaves); kNoVertex for a missing side,
  VertexId cut_r = kNoVertex;  // at least one is present
  float position_t[3] = {0, 0, 0};
  RefineInfo info_t{}, info_u{};
  bool has_normal = false;  // required when the hierarchy keeps normals
  float normal_t[3] = {0, 0, 0};
  bool has_color = false;  // required when the hierarchy keeps colors
  uint8_t color_t[4] = {0, 0, 0, 0};
};

// The vsplit packet of internal node `node` of a complete model: ids from model.id(), cut ids from the
// cut_left / cut_right leaf indices. Throws pms::Error for a leaf or an index out of range.
SplitRecord split_record(const ModelData& model, uint32_t node);

}  // namespace pms
