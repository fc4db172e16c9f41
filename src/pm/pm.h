// The view-dependent progressive-mesh model (Kim, Lee, Kobbelt 2005 §4, §6; Hoppe 1997 §4).
// Everything every mode shares: vertex ids, the packed hierarchy, refinement info and the .pms file.
#pragma once
#include <bit>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace pms {

constexpr uint32_t kNone = UINT32_MAX;

// <tree-id, node-id> (DESIGN.md §2): tree = base-mesh vertex index, node = heap index with an
// implicit leading 1 (root 1, children 2n and 2n+1). Parent and children need no transmission.
struct VertexId {
  uint32_t tree = 0;
  uint64_t node = 1;

  VertexId parent() const { return {tree, node >> 1}; }
  VertexId child(int which) const { return {tree, (node << 1) | uint64_t(which)}; }
  int depth() const { return 63 - std::countl_zero(node); }
  bool is_root() const { return node == 1; }
  friend bool operator==(VertexId, VertexId) = default;
};

// ActiveAncestor by right shift (kim-lee-kobbelt §4): the ancestor of `v` at `depth`.
inline VertexId ancestor_at_depth(VertexId v, int depth) { return {v.tree, v.node >> (v.depth() - depth)}; }

inline bool is_ancestor_or_self(VertexId a, VertexId b) {
  if (a.tree != b.tree) return false;
  const int d = b.depth() - a.depth();
  return d >= 0 && (b.node >> d) == a.node;
}

// Hoppe-97 refinement info as stored and sent: quantized so every bound still holds after
// decoding (radius, mu, delta and cone angle rounded up). All modes evaluate these decoded
// values, so local, sender-, receiver-driven and DAG refinement agree on the mesh for a view.
// The precision is what a vsplit packet carries (65 bits per node with a cone, 43 without: two
// nodes per packet are most of a packet), so the file holds exactly what the wire can say.
struct RefineInfo {
  uint16_t radius;      // half-float bits of radius / scale, rounded toward +inf to kLengthKeptBits
  uint16_t mu;          // same, of mu / scale (uniform deviation)
  uint16_t delta;       // same, of delta / scale (deviation along the normal)
  uint16_t cone_x;      // octahedral-encoded cone axis: int16 in [-kAxisSteps, kAxisSteps] per coordinate
  uint16_t cone_y;
  uint16_t cone_angle;  // half-angle in units of (pi/2) / (kConeSteps + 1), rounded up; kNoCone = never back-facing
  friend bool operator==(const RefineInfo&, const RefineInfo&) = default;
};
static_assert(sizeof(RefineInfo) == 12);
constexpr uint16_t kNoCone = 0xFFFF;        // the axis is then +z (0, 0)
constexpr uint32_t kLengthDroppedBits = 4;  // low half-float mantissa bits that are always 0
constexpr uint32_t kLengthBits = 15 - kLengthDroppedBits;  // what is left without the sign
constexpr uint32_t kAxisBits = 11;          // per octahedral coordinate, sign included
constexpr int16_t kAxisSteps = (1 << (kAxisBits - 1)) - 1;
constexpr uint32_t kConeAngleBits = 10;
constexpr uint16_t kConeSteps = (1 << kConeAngleBits) - 2;  // largest cone_angle below pi/2

// False for values quantize_refine never produces (negative or NaN lengths, dropped bits set, axis
// or angle out of range, a no-cone axis other than +z): the file reader and wire decoder reject them.
bool is_canonical(const RefineInfo& info);

// Decoded, in model units.
struct RefineBounds {
  float radius = 0;     // sphere around the node's position bounding its descendants' input faces
  float mu = 0;         // deviation space D(mu, delta) around the normal (Hoppe 1997 §4.3)
  float delta = 0;
  float axis[3] = {0, 0, 1};
  float cone_angle = 0; // radians; >= pi/2 (or kNoCone) means the cone test never culls
};

RefineInfo quantize_refine(const RefineBounds& bounds, float scale);
RefineBounds dequantize_refine(const RefineInfo& info, float scale);

// Half-float helpers (exposed for tests): round toward +inf so decoded >= value for value >= 0.
uint16_t half_from_float_up(float value);
float float_from_half(uint16_t half);

// What the builder recorded; stored in the file's META section as JSON.
struct BuildStats {
  std::string input_name;
  std::string tool_version;
  std::string options;          // e.g. "balanced base_vertices=0"
  uint64_t input_vertices = 0;  // of the cleaned input
  uint64_t input_faces = 0;
  uint64_t base_vertices = 0;
  uint64_t base_faces = 0;
  uint64_t vsplits = 0;
  uint32_t tree_id_bits = 0;    // ceil(log2(base_vertices))
  uint32_t node_id_bits = 0;    // max depth (the implicit leading 1 is not counted)
  uint32_t max_depth = 0;
  double seconds = 0;           // build time, load excluded
  std::string clean_report;     // human summary of what cleaning changed
};

// The hierarchy, owned. Nodes are packed breadth-first by depth (parent index < child index):
// indices [0, root_count) are the roots = base-mesh vertices, tree-id = index.
// Internal node n has children first_child[n] (v_t, node-id 2k) and first_child[n] + 1
// (v_u, node-id 2k+1). v_u keeps the parent's position (half-edge collapse v_t -> v_u), so a
// split only introduces v_t's position.
struct Hierarchy {
  uint32_t root_count = 0;
  std::vector<uint32_t> base_faces;    // 3 root indices per face, CCW
  std::vector<uint32_t> parent;        // per node; kNone for roots
  std::vector<uint32_t> first_child;   // per node; kNone for leaves
  std::vector<float> position;         // 3 per node
  std::vector<uint32_t> cut_left;      // per node: leaf index of v̂_l; kNone for leaves or no left face
  std::vector<uint32_t> cut_right;     // per node: leaf index of v̂_r; kNone for leaves or no right face
  std::vector<RefineInfo> refine;      // per node
  std::vector<uint32_t> leaf_vertex;   // per node: vertex index in the cleaned input; kNone if internal
  std::vector<uint32_t> split_order;   // internal nodes in PM order (reverse of collapse order)
  std::vector<float> normals;          // optional: 3 per node (internal nodes: survivor leaf's)
  std::vector<uint8_t> colors;         // optional: 4 per node
  float bbox_min[3] = {0, 0, 0};
  float bbox_max[3] = {0, 0, 0};
  float scale = 1;                     // bounding-box diagonal; refinement info is relative to it

  // Derived from the structure (not stored in the file): ids per node.
  std::vector<uint32_t> tree_id;
  std::vector<uint64_t> node_id;

  size_t node_count() const { return parent.size(); }
  size_t leaf_count() const;
  bool is_leaf(uint32_t n) const { return first_child[n] == kNone; }
  VertexId id(uint32_t n) const { return {tree_id[n], node_id[n]}; }
  void compute_ids();                  // fills tree_id/node_id from parent/first_child
  uint32_t find(VertexId id) const;    // node index by walking from the root; kNone if absent
};

// Bits needed to write ids, as reported by build/info (kim-lee-kobbelt §6.2 Table 1).
uint32_t tree_id_bits(uint64_t root_count);
uint32_t max_depth(const Hierarchy& h);

// Read-only view of a model: either a Hierarchy in memory or a memory-mapped .pms file.
struct ModelView {
  uint32_t root_count = 0;
  std::span<const uint32_t> base_faces;
  std::span<const uint32_t> parent, first_child;
  std::span<const float> position;
  std::span<const uint32_t> cut_left, cut_right;
  std::span<const RefineInfo> refine;
  std::span<const uint32_t> leaf_vertex;
  std::span<const uint32_t> split_order;
  std::span<const float> normals;
  std::span<const uint8_t> colors;
  std::span<const uint32_t> tree_id;
  std::span<const uint64_t> node_id;
  const float* bbox_min = nullptr;
  const float* bbox_max = nullptr;
  float scale = 1;

  size_t node_count() const { return parent.size(); }
  bool is_leaf(uint32_t n) const { return first_child[n] == kNone; }
  VertexId id(uint32_t n) const { return {tree_id[n], node_id[n]}; }
  uint32_t find(VertexId id) const;
};

ModelView view_of(const Hierarchy& h);

// The .pms file (DESIGN.md §3): see docs/pms-format.md for the layout.
void write_pms(const std::string& path, const Hierarchy& h, const BuildStats& stats);

class PmsFile {
 public:
  // Memory-maps and validates every section and index; throws pms::Error("PATH: section X: ...").
  static std::unique_ptr<PmsFile> open(const std::string& path);
  // Same over bytes in memory (used by tests and the fuzz target); the bytes are copied.
  static std::unique_ptr<PmsFile> from_bytes(const std::string& name, const uint8_t* data, size_t size);
  ~PmsFile();
  PmsFile(const PmsFile&) = delete;
  PmsFile& operator=(const PmsFile&) = delete;

  const ModelView& view() const { return view_; }
  const BuildStats& stats() const { return stats_; }
  uint64_t file_size() const { return size_; }

 private:
  PmsFile() = default;
  void parse(const std::string& name);
  const uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
  bool mapped_ = false;
  std::vector<uint8_t> owned_;  // when not memory-mapped
  std::vector<uint32_t> tree_id_;
  std::vector<uint64_t> node_id_;
  ModelView view_;
  BuildStats stats_;
};

}  // namespace pms
