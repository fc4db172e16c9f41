// Semantic checks of a model before anything uses it: the reader runs them on every file it
// opens (after the layout and checksums) and the writer on every hierarchy it writes, so a file
// that passes is one the refinement code can index blindly. One function per section family,
// each a single O(n) pass; the first problem found is reported with the section and node.
#include <cmath>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/hierarchy_internal.h"
#include "spm/pms_format_internal.h"
#include "spm/refine_info.h"
#include "spm/vertex_id.h"

namespace pms::format {

void section_error(const std::string& where, Section section, const std::string& what) {
  fail(where, std::string("section ") + kSections[section].tag + ": " + what);
}

namespace {

void check_head(const std::string& where, const ModelData& m) {
  if (m.root_count == 0) section_error(where, Head, "no base vertices");
  if (m.root_count > m.node_count())
    section_error(where, Head, str(m.root_count) + " base vertices but only " + str(m.node_count()) + " nodes");
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(m.bbox_min[k]) || !std::isfinite(m.bbox_max[k]))
      section_error(where, Head, "bounding box is not finite");
  if (!std::isfinite(m.scale) || m.scale < 0) section_error(where, Head, "scale is not a finite non-negative number");
}

// Roots have no parent; every other node's parent precedes it (kim-lee-kobbelt §6.1 packing).
void check_parents(const std::string& where, const ModelData& m) {
  for (uint32_t i = 0; i < m.node_count(); ++i) {
    const uint32_t p = m.parent[i];
    if (i < m.root_count) {
      if (p != kNone) section_error(where, Parent, "root " + str(i) + " has parent " + str(p));
    } else if (p == kNone) {
      section_error(where, Parent, "node " + str(i) + " is not a root but has no parent");
    } else if (p >= i) {
      section_error(where, Parent, "node " + str(i) + ": parent " + str(p) + " is not before it in the array");
    }
  }
}

// Children are adjacent, after their parent, and agree with the parent links both ways: with
// check_parents this makes the arrays a binary forest.
void check_children(const std::string& where, const ModelData& m) {
  const uint64_t n = m.node_count();
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t c = m.first_child[i];
    if (c != kNone) {
      if (c <= i || uint64_t(c) + 1 >= n)
        section_error(where, Children,
                      "node " + str(i) + ": children " + str(c) + ", " + str(uint64_t(c) + 1) +
                          " are not after it inside the array");
      if (m.parent[c] != i || m.parent[c + 1] != i)
        section_error(
            where, Children,
            "node " + str(i) + ": children " + str(c) + ", " + str(c + 1) + " do not name it as their parent");
    }
    if (i < m.root_count) continue;
    const uint32_t p = m.parent[i], pc = m.first_child[p];
    if (pc == kNone || (i != pc && i != pc + 1))
      section_error(where, Children, "node " + str(i) + " is not a child of its parent " + str(p));
  }
}

// kim-lee-kobbelt §6.1: packed breadth-first, so the active-tag window only moves right.
void check_breadth_first(const std::string& where, const std::vector<uint64_t>& node_id) {
  int previous = 0;
  for (size_t i = 0; i < node_id.size(); ++i) {
    const int depth = VertexId{0, node_id[i]}.depth();
    if (depth < previous)
      section_error(where, Parent,
                    "node " + str(i) + " at depth " + str(depth) + " follows a node at depth " + str(previous) +
                        " (nodes must be packed breadth-first by depth)");
    previous = depth;
  }
}

// Leaves name the input vertices, each exactly once; internal nodes name none.
void check_leaves(const std::string& where, const ModelData& m) {
  const size_t leaves = (m.node_count() + m.root_count) / 2;  // a binary forest, checked above
  std::vector<uint8_t> seen(leaves, 0);
  for (uint32_t i = 0; i < m.node_count(); ++i) {
    const uint32_t v = m.leaf_vertex[i];
    if (!m.is_leaf(i)) {
      if (v != kNone) section_error(where, Leaf, "internal node " + str(i) + " has input vertex " + str(v));
      continue;
    }
    if (v == kNone) section_error(where, Leaf, "leaf " + str(i) + " has no input vertex");
    if (v >= leaves)
      section_error(where, Leaf, "leaf " + str(i) + ": input vertex " + str(v) + " >= leaf count " + str(leaves));
    if (seen[v]) section_error(where, Leaf, "input vertex " + str(v) + " belongs to two leaves (not a permutation)");
    seen[v] = 1;
  }
}

// Fundamental cut vertices (kim-lee-kobbelt §4): leaves outside the split node's own subtree,
// at least one per split (a boundary split has only one).
void check_cuts(const std::string& where, const ModelData& m, const std::vector<uint32_t>& tree_id,
                const std::vector<uint64_t>& node_id) {
  const Section sides[2] = {CutLeft, CutRight};
  for (uint32_t i = 0; i < m.node_count(); ++i) {
    const uint32_t cuts[2] = {m.cut_left[i], m.cut_right[i]};
    for (int s = 0; s < 2; ++s) {
      const uint32_t c = cuts[s];
      if (c == kNone) continue;
      if (m.is_leaf(i)) section_error(where, sides[s], "leaf " + str(i) + " has cut vertex " + str(c));
      if (c >= m.node_count())
        section_error(where, sides[s], "node " + str(i) + ": cut vertex " + str(c) + " out of range");
      if (!m.is_leaf(c)) section_error(where, sides[s], "node " + str(i) + ": cut vertex " + str(c) + " is not a leaf");
      if (is_ancestor_or_self({tree_id[i], node_id[i]}, {tree_id[c], node_id[c]}))
        section_error(where, sides[s], "node " + str(i) + ": cut vertex " + str(c) + " lies below the node itself");
    }
    if (!m.is_leaf(i) && cuts[0] == kNone && cuts[1] == kNone)
      section_error(where, CutLeft, "node " + str(i) + ": a split needs at least one cut vertex, both are missing");
  }
}

void check_base(const std::string& where, const ModelData& m) {
  for (size_t k = 0; k < m.base_faces.size(); ++k)
    if (m.base_faces[k] >= m.root_count)
      section_error(where, Base,
                    "face " + str(k / 3) + ": vertex " + str(m.base_faces[k]) + " is not a base vertex (" +
                        str(m.root_count) + " roots)");
}

// PM order: every internal node once, each after its parent, so splits apply front to back.
void check_split_order(const std::string& where, const ModelData& m) {
  const size_t internal = (m.node_count() - m.root_count) / 2;
  if (m.split_order.size() != internal)
    section_error(where, SplitOrder, str(m.split_order.size()) + " entries for " + str(internal) + " internal nodes");
  std::vector<uint8_t> done(m.node_count(), 0);
  for (size_t k = 0; k < internal; ++k) {
    const uint32_t v = m.split_order[k];
    if (v >= m.node_count()) section_error(where, SplitOrder, "entry " + str(k) + ": node " + str(v) + " out of range");
    if (m.is_leaf(v)) section_error(where, SplitOrder, "entry " + str(k) + ": node " + str(v) + " is a leaf");
    if (done[v]) section_error(where, SplitOrder, "node " + str(v) + " appears twice");
    const uint32_t p = m.parent[v];
    if (p != kNone && !done[p])
      section_error(where, SplitOrder, "node " + str(v) + " comes before its parent " + str(p));
    done[v] = 1;
  }
}

void check_finite(const std::string& where, Section section, std::span<const float> values) {
  for (size_t k = 0; k < values.size(); ++k)
    if (!std::isfinite(values[k])) section_error(where, section, "node " + str(k / 3) + ": value is not finite");
}

// Only values the quantizer produces: lengths non-negative (infinity allowed: "always refine") at the
// stored precision, axis and angle in range. The wire carries exactly these, nothing finer.
void check_refine(const std::string& where, const ModelData& m) {
  for (size_t i = 0; i < m.refine.size(); ++i)
    if (!is_canonical(m.refine[i]))
      section_error(where, Refine,
                    "node " + str(i) + ": a length is negative, NaN or finer than stored, or the cone is out of range");
}

}  // namespace

void validate_model(const std::string& where, const ModelData& m, std::vector<uint32_t>& tree_id,
                    std::vector<uint64_t>& node_id) {
  check_head(where, m);
  check_parents(where, m);
  check_children(where, m);
  tree_id.assign(m.node_count(), 0);
  node_id.assign(m.node_count(), 0);
  detail::compute_ids(m.root_count, m.first_child, tree_id, node_id, where + ": section CHLD");
  check_breadth_first(where, node_id);
  check_leaves(where, m);
  check_cuts(where, m, tree_id, node_id);
  check_base(where, m);
  check_split_order(where, m);
  check_finite(where, Position, m.position);
  check_finite(where, Normal, m.normals);
  check_refine(where, m);
}

}  // namespace pms::format
