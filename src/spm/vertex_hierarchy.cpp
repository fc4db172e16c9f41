// The client's partial vertex hierarchy: UpdateVHierarchy of kim-lee-kobbelt 2005 §5.3 over flat slot
// arrays, with an open-addressing VertexId -> slot map (the packets name nodes by <tree-id, node-id>).
#include <algorithm>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

constexpr const char* kWhere = "vertex hierarchy";
constexpr uint32_t kMaxSlots = kNone - 2;  // slots and slot + 1 must stay below kNone

uint64_t hash_id(VertexId id) {
  uint64_t h = id.node * 0x9E3779B97F4A7C15ull ^ (uint64_t(id.tree) * 0xC2B2AE3D27D4EB4Full);
  return h ^ (h >> 29);
}

}  // namespace

VertexHierarchy::VertexHierarchy(bool has_normals, bool has_colors)
    : has_normals_(has_normals), has_colors_(has_colors) {}

void VertexHierarchy::reserve(size_t slots) {
  id_.reserve(slots);
  position_.reserve(3 * slots);
  info_.reserve(slots);
  parent_.reserve(slots);
  first_child_.reserve(slots);
  cut_.reserve(slots);
  if (has_normals_) normal_.reserve(3 * slots);
  if (has_colors_) color_.reserve(4 * slots);
}

uint32_t VertexHierarchy::find(VertexId id) const {
  if (table_.empty()) return kNone;
  const size_t mask = table_.size() - 1;
  for (size_t b = hash_id(id) & mask;; b = (b + 1) & mask) {
    const uint32_t slot = table_[b];
    if (slot == kNone || id_[slot] == id) return slot;
  }
}

void VertexHierarchy::insert(uint32_t slot) {
  const size_t mask = table_.size() - 1;
  size_t b = hash_id(id_[slot]) & mask;
  while (table_[b] != kNone) b = (b + 1) & mask;
  table_[b] = slot;
}

void VertexHierarchy::grow_table() {
  table_.assign(std::max<size_t>(64, 2 * table_.size()), kNone);
  for (uint32_t slot = 0; slot < size(); ++slot) insert(slot);
}

uint32_t VertexHierarchy::push_slot(VertexId id, const float position[3], const RefineInfo& info, uint32_t parent,
                                    const float* normal, const uint8_t* color) {
  if (id_.size() >= kMaxSlots) fail(kWhere, "too many nodes");
  const uint32_t slot = size();
  id_.push_back(id);
  position_.insert(position_.end(), position, position + 3);
  info_.push_back(info);
  parent_.push_back(parent);
  first_child_.push_back(kNone);
  cut_.push_back(kNoVertex);
  if (has_normals_) normal_.insert(normal_.end(), normal, normal + 3);
  if (has_colors_) color_.insert(color_.end(), color, color + 4);
  if (2 * (size_t(slot) + 1) > table_.size()) grow_table();  // grow_table() also inserts `slot`
  else insert(slot);
  return slot;
}

uint32_t VertexHierarchy::add_root(VertexId id, const float position[3], const RefineInfo& info, const float* normal,
                                   const uint8_t* color) {
  if (!id.is_root() || id.tree != root_count())
    fail(kWhere, "root " + to_string(id) + " out of order (expected <" + std::to_string(root_count()) + ",1>)");
  if ((has_normals_ && !normal) || (has_colors_ && !color)) fail(kWhere, "root " + to_string(id) + " lacks attributes");
  const uint32_t slot = push_slot(id, position, info, kNone, normal, color);
  root_slot_.push_back(slot);
  return slot;
}

uint32_t VertexHierarchy::add_split(const SplitRecord& split) {
  // The message is built only on failure: this runs for every packet a client receives.
  const auto reject = [&](const std::string& why) { fail(kWhere, "vsplit " + to_string(split.vs) + ": " + why); };
  const uint32_t s = find(split.vs);
  if (s == kNone) reject("unknown node");
  if (!is_leaf(s)) reject("node already split");
  if (split.vs.depth() >= 63) reject("node too deep for 64-bit node ids");
  if (!is_vertex(split.cut_l) && !is_vertex(split.cut_r)) reject("no fundamental cut vertex");
  for (VertexId cut : {split.cut_l, split.cut_r}) {
    if (!is_vertex(cut)) continue;
    // A cut vertex is a corner of f_l / f_r that does not collapse into v_s.
    if (cut.tree >= root_count() || is_ancestor_or_self(split.vs, cut)) reject("invalid cut vertex " + to_string(cut));
  }
  if ((has_normals_ && !split.has_normal) || (has_colors_ && !split.has_color)) reject("packet lacks attributes");

  // v_u inherits v_s's geometry; copy before push_slot() may reallocate the arrays.
  float position_u[3], normal_u[3] = {0, 0, 0};
  uint8_t color_u[4] = {0, 0, 0, 0};
  std::copy_n(position(s), 3, position_u);
  if (has_normals_) std::copy_n(normal(s), 3, normal_u);
  if (has_colors_) std::copy_n(color(s), 4, color_u);
  const uint32_t t = push_slot(split.vs.child(0), split.position_t, split.info_t, s, split.normal_t, split.color_t);
  const uint32_t u = push_slot(split.vs.child(1), position_u, split.info_u, s, normal_u, color_u);
  cut_[t] = split.cut_l;
  cut_[u] = split.cut_r;
  first_child_[s] = t;
  return t;
}

VertexHierarchy VertexHierarchy::from_model(const ModelData& model) {
  check_node_arrays(model);
  const bool normals = !model.normals.empty(), colors = !model.colors.empty();
  VertexHierarchy h(normals, colors);
  h.reserve(model.root_count);
  for (uint32_t r = 0; r < model.root_count; ++r)
    h.add_root(model.id(r), &model.position[3 * size_t(r)], model.refine[r],
               normals ? &model.normals[3 * size_t(r)] : nullptr, colors ? &model.colors[4 * size_t(r)] : nullptr);
  return h;
}

}  // namespace pms
