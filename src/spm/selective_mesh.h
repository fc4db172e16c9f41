// The selectively refined mesh over a client's vertex hierarchy (kim-lee-kobbelt 2005 §4–5; Kim & Lee 2001,
// truly selective refinement). Conventions (v_t / v_u, f_l / f_r, fan order) are those of docs/internals.md.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/huge_pages.h"
#include "spm/slot_array.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {

struct VSplitResult {
  bool done = false;
  uint32_t needs = kNone;  // when !done: slot of an active leaf whose vsplit packet must arrive first
};

// The current mesh as flat arrays: output vertex i is hierarchy slot slots[i].
struct MeshArrays {
  std::vector<float> positions;   // 3 per vertex
  std::vector<float> normals;     // 3 per vertex when the hierarchy keeps normals
  std::vector<uint8_t> colors;    // 4 per vertex when the hierarchy keeps colors
  std::vector<uint32_t> indices;  // 3 per face, CCW
  std::vector<uint32_t> slots;
};

// The selectively refined mesh over the active slots of a VertexHierarchy (SelVSplit / SelECol,
// kim-lee-kobbelt §5.3; Kim & Lee 2001). Triangles are flat corner triples with a free list; every
// active vertex lists its incident faces in fan order in its own cache-line record (a pool block for
// long fans), so an operation reads a fan as one short array instead of a chain of dependent twin
// lookups, and a split cuts it into two ranges without ordering it. A face keeps its index while its
// corners move up and down the hierarchy; the faces one split created know each other (partner_).
class SelectiveMesh {
 public:
  // `base_faces`: 3 tree-ids (= root indices) per face, CCW. Every root of `hierarchy` must be used and
  // the faces must form an oriented 2-manifold (boundaries allowed); throws pms::Error otherwise.
  // `hierarchy` must outlive the mesh; it may keep growing (add_split) in the meantime.
  SelectiveMesh(const VertexHierarchy& hierarchy, std::span<const uint32_t> base_faces);

  // ActiveAncestor (kim-lee-kobbelt §4): the active node on the path from v's root to v; kNone when the
  // front does not cross that path (inconsistent data).
  uint32_t active_ancestor(VertexId v) const;

  // SelVSplit of the active, split-known node `slot`, splitting v_l = v_r first as the partial order of
  // §5.3 requires. Returns !done with the leaf that still needs its packet when a split in that chain is
  // not known yet (the mesh then stays valid, possibly with some of the chain already split). Throws
  // pms::Error when `slot` is not active or the packets contradict the mesh.
  VSplitResult vsplit(uint32_t slot);

  // SelECol of the known internal node `parent_slot` (pms::Error if it has no known children). Returns
  // false, changing nothing, unless both children are active and adjacent with f_l / f_r apexes
  // ActiveAncestor(v̂_l) / ActiveAncestor(v̂_r), the partial order holds backwards (no performed split
  // would see its two cut vertices merge: that split's subtree must collapse first), and the result is
  // an oriented 2-manifold without isolated vertices (link condition).
  bool ecol(uint32_t parent_slot);

  // An operation is a chain of dependent cache misses: the node's child and record, then its faces'
  // corners, then the neighbours' records. A caller that knows its next operations overlaps those
  // chains: for each operation i it runs stage k for operation i + kPrefetchAhead[k], every stage
  // (ecol: the collapse order's next ones). Any slot is allowed; a hint changes nothing.
  static constexpr int kPrefetchStages = 4;
  static constexpr uint32_t kPrefetchAhead[kPrefetchStages] = {16, 8, 4, 2};
  void prefetch_vsplit(uint32_t slot, int stage) const;
  void prefetch_ecol(uint32_t parent_slot, int stage) const;

  bool is_active(uint32_t slot) const { return slot < vertex_.size() && is_active_recorded(slot); }
  // is_active() of a slot known to have a record: a root, or a child of a node that was ever split (the
  // adaptation walk asks it of every node it reaches, and reaches no others).
  bool is_active_recorded(uint32_t slot) const { return (active_bits_[slot >> 6] >> (slot & 63) & 1) != 0; }
  std::span<const uint32_t> active_vertices() const { return active_; }
  size_t vertex_count() const { return active_.size(); }
  size_t face_count() const { return face_count_; }
  // Faces are [0, face_capacity()); dead ones (on the free list) are skipped by face_alive().
  uint32_t face_capacity() const { return uint32_t(corner_.size() / 3); }
  bool face_alive(uint32_t f) const { return corner_[3 * size_t(f)] != kNone; }
  const uint32_t* face(uint32_t f) const { return &corner_[3 * size_t(f)]; }  // 3 slots, CCW
  const VertexHierarchy& hierarchy() const { return *hierarchy_; }
  // Counts activations and deactivations: equal values mean the same active front (the adaptation
  // loop's steady-frame test).
  uint64_t changes() const { return changes_; }

  // Vertices in active_vertices() order.
  void extract(MeshArrays& out) const;
  // Audit for tests: each directed edge once, partners symmetric, every active vertex lists exactly its
  // faces and they form one fan, the active set a front of the hierarchy that respects the partial order
  // (no performed split whose cut vertices share an active ancestor). On failure `why` (if given) says what.
  bool check_invariants(std::string* why) const;

 private:
  // v's corner of `face` seen from v: the face reads (v, next, prev) CCW; corner_[3 * face + k] == v.
  struct Corner {
    uint32_t face, k, next, prev;
  };
  // Per slot, one cache line: a copy of the node's id (a neighbour's id costs no extra miss) and its
  // incident faces, inline up to kInlineFaces, else in a pool_ block of `capacity` (a power of two)
  // entries whose start inline_faces[0] holds. capacity == 0: inactive. The faces are in CCW fan order,
  // an open fan's from the face after its gap (docs/internals.md, "Engine layout").
  static constexpr uint32_t kInlineFaces = 10;
  struct alignas(64) VertexRecord {
    uint64_t node = 0;
    uint32_t tree = 0;
    uint32_t size = 0, capacity = 0, active_pos = kNone;
    uint32_t inline_faces[kInlineFaces] = {};
  };
  static_assert(sizeof(VertexRecord) == 64);
  static constexpr int kRecordArrayKind = 1;  // SlotArray's kind: blocks go back to the next mesh's records

  void reserve_faces() {
    if (reserved_for_ != hierarchy_->size()) reserve_new_faces();
  }
  void reserve_new_faces();
  void grow_records(uint32_t end) {  // records for slots [0, end) at least
    if (end > vertex_.size()) add_records(end);
  }
  void add_records(uint32_t end);
  void prefetch_record(uint32_t v) const;
  enum class FanStage { corners, split_neighbours, collapse_reads };
  void prefetch_fan(uint32_t v, FanStage stage) const;
  void load_corners(uint32_t v, std::vector<Corner>& corners) const;
  static bool order_fan(std::vector<Corner>& fan, std::vector<Corner>& ordered, std::vector<uint32_t>& successor);
  static uint32_t open_end(std::vector<Corner>& fan);  // an open fan's far end (no corner's next), else kNone
  static void prepare_lookup(std::vector<Corner>& fan);
  static uint32_t find_next(const std::vector<Corner>& fan, uint32_t w);  // index of the corner with `next` w
  std::pair<uint32_t, uint32_t> cut_ancestors(VertexId cut_l, VertexId cut_r, uint32_t slot) const;  // over fan_ (slot)
  void split_fan(uint32_t s, uint32_t l, uint32_t r);                                                // over fan_ (s)
  bool split_between(uint32_t s, VertexId cut_l, VertexId cut_r);  // vsplit's common case, before fan_ is read
  // What split_between read of v_s's fan: per listed face, v_s's corner and the one after it.
  struct FanReading {
    const uint32_t *face, *k, *next;
    uint32_t size;
  };
  bool split_one_side(uint32_t s, const FanReading& fan, uint64_t match, bool left);
  void join_fans(uint32_t p, uint32_t fl, uint32_t fr, bool t_open, bool u_open);  // over fan_ (t), fan_u_ (u)
  void put_in_fan_order(uint32_t v);       // the lists' order, restored the slow way
  bool repeats_directed_edge(uint32_t v);  // over fan_ (v): a bad base mesh
  void start_after_gap(uint32_t v);
  bool breaks_split_order(uint32_t u) const;  // over fan_ (t)
  // Over fan_ (t) and fan_u_ (u), whose open ends (kNone: closed) are given.
  bool link_condition(uint32_t t, uint32_t l, uint32_t r, uint32_t t_end, uint32_t u_end);
  uint32_t new_face(uint32_t a, uint32_t b, uint32_t c);
  void add_free_faces();
  void free_face(uint32_t f);
  uint32_t alloc_block(uint32_t capacity);
  void free_block(uint32_t begin, uint32_t capacity);
  uint32_t* faces_of(VertexRecord& v) {
    return v.capacity <= kInlineFaces ? v.inline_faces : &pool_[v.inline_faces[0]];
  }
  const uint32_t* faces_of(const VertexRecord& v) const {
    return v.capacity <= kInlineFaces ? v.inline_faces : &pool_[v.inline_faces[0]];
  }
  VertexId id_of(uint32_t v) const { return {vertex_[v].tree, vertex_[v].node}; }
  uint32_t* assign_faces(uint32_t v, uint32_t count);  // a fresh list of `count` entries for v
  void append_face(uint32_t v, uint32_t f);
  // f into v's list right after (or before) the face `anchor`, which the list holds.
  void insert_face(uint32_t v, uint32_t f, uint32_t anchor, bool after);
  static bool insert_inline_face(VertexRecord& record, uint32_t f, uint32_t anchor, bool after);
  void remove_face(uint32_t v, uint32_t f);  // keeps the others' order
  void activate(uint32_t v, VertexId id);
  void deactivate(uint32_t v);
  bool pool_blocks_disjoint(std::vector<std::pair<uint32_t, uint32_t>>& blocks) const;              // audit
  static bool in_fan_order(const uint32_t* list, const std::vector<Corner>& ordered, bool closed);  // audit

  const VertexHierarchy* hierarchy_;
  // The big arrays are on huge pages (common/huge_pages.h): operations read them at random. Recycled:
  // the next mesh gets their pages back, mapped.
  RecycledVector<uint32_t> corner_;   // 3 slots per face; a dead face holds kNone, next free face
  RecycledVector<uint32_t> partner_;  // per face: the other face of the split that made it (f_l <-> f_r)
  uint32_t free_face_ = kNone;
  uint64_t changes_ = 0;
  size_t face_count_ = 0;
  size_t base_face_count_ = 0;
  // Per slot, never initialised as a whole (spm/slot_array.h): a record is written when its vertex
  // activates and read only while it is active, so a fresh mesh pays for what it refines, not for the
  // model.
  SlotArray<VertexRecord, kRecordArrayKind> vertex_;
  std::vector<uint64_t> active_bits_;          // per slot, 1 = active: the adaptation walk asks for every node
  uint32_t reserved_for_ = 0;                  // hierarchy size the face arrays were reserved for
  RecycledVector<uint32_t> pool_;              // incident-face blocks; a free block holds the next free one
  uint32_t free_block_[32];                    // per log2(capacity): first free block
  RecycledVector<uint32_t> active_;            // active slots
  std::vector<Corner> fan_, fan_u_, ordered_;  // scratch, kept to avoid allocating per operation
  std::vector<uint32_t> chain_;                // vsplit's forced chain
  std::vector<uint32_t> successor_;            // order_fan's
};

}  // namespace pms
