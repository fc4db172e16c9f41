// The vertex hierarchy a client knows (kim-lee-kobbelt 2005 §5.3): the nodes received so far.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <vector>

#include "common/huge_pages.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms {

// The client's partial vertex hierarchy (UpdateVHierarchy, kim-lee-kobbelt §5.3): every node received so
// far lives in a slot of flat arrays; children are allocated as an adjacent pair (v_t, v_u = v_t + 1)
// when their split arrives, so a known node with no children is a leaf of what is known (IsLeaf).
class VertexHierarchy {
 public:
  explicit VertexHierarchy(bool has_normals = false, bool has_colors = false);

  // Loads the roots (base-mesh vertices) of a complete model; splits are added as they "arrive".
  static VertexHierarchy from_model(const ModelData& model);

  // Roots must come in tree-id order (tree-id = base-vertex index, docs/internals.md, "Vertex ids"). `normal`/`color`
  // are required when the hierarchy keeps them. Returns the slot.
  uint32_t add_root(VertexId id, const float position[3], const RefineInfo& info, const float* normal = nullptr,
                    const uint8_t* color = nullptr);
  // Attaches v_t and v_u below v_s; returns v_t's slot (v_u's is the next one). Throws pms::Error for
  // an unknown or already split v_s, a record without cut vertices, or cut ids that cannot be leaves
  // outside v_s's subtree.
  uint32_t add_split(const SplitRecord& split);

  uint32_t find(VertexId id) const;  // slot, or kNone when the node is not known
  void reserve(size_t slots);

  uint32_t size() const { return uint32_t(id_.size()); }
  uint32_t root_count() const { return uint32_t(root_slot_.size()); }
  uint32_t root_slot(uint32_t tree) const { return root_slot_[tree]; }
  VertexId id(uint32_t slot) const { return id_[slot]; }
  const float* position(uint32_t slot) const { return &position_[3 * size_t(slot)]; }
  const RefineInfo& refine(uint32_t slot) const { return info_[slot]; }
  uint32_t parent(uint32_t slot) const { return parent_[slot]; }
  uint32_t first_child(uint32_t slot) const { return first_child_[slot]; }
  bool is_leaf(uint32_t slot) const { return first_child_[slot] == kNone; }
  // v̂_l / v̂_r of a split node (kNoVertex for a missing side); only valid when !is_leaf(slot).
  VertexId cut_left(uint32_t slot) const { return cut_[first_child_[slot]]; }
  VertexId cut_right(uint32_t slot) const { return cut_[first_child_[slot] + 1]; }
  // The same, stored with the children: v̂_l for a first child v_t, v̂_r for v_u.
  VertexId cut_of_child(uint32_t child) const { return cut_[child]; }
  // For prefetching only: where first_child(slot) and cut_of_child(child) live until the hierarchy grows.
  const uint32_t* first_child_address(uint32_t slot) const { return &first_child_[slot]; }
  const VertexId* cut_address(uint32_t child) const { return &cut_[child]; }
  bool has_normals() const { return has_normals_; }
  bool has_colors() const { return has_colors_; }
  const float* normal(uint32_t slot) const { return &normal_[3 * size_t(slot)]; }
  const uint8_t* color(uint32_t slot) const { return &color_[4 * size_t(slot)]; }

 private:
  uint32_t push_slot(VertexId id, const float position[3], const RefineInfo& info, uint32_t parent, const float* normal,
                     const uint8_t* color);
  void insert(uint32_t slot);
  void grow_table();

  bool has_normals_, has_colors_;
  // Per-slot arrays on huge pages (common/huge_pages.h): the engine and the adaptation loop read them
  // at random.
  BigVector<VertexId> id_;
  BigVector<float> position_;
  BigVector<RefineInfo> info_;
  BigVector<uint32_t> parent_;
  BigVector<uint32_t> first_child_;
  // The cuts of a split are stored with its children pair: cut_[v_t] = v̂_l, cut_[v_u] = v̂_r, so no
  // slot pays for them before its split is known.
  BigVector<VertexId> cut_;
  BigVector<float> normal_;
  BigVector<uint8_t> color_;
  std::vector<uint32_t> root_slot_;  // per tree-id
  // Open addressing with linear probing, VertexId -> slot; buckets hold slots (kNone = empty) and keys
  // are read back from id_, so a bucket costs 4 bytes. Power-of-two size, at most half full.
  BigVector<uint32_t> table_;
};

}  // namespace pms
