// Truly selective refinement over a partial vertex hierarchy:
//   Kim & Lee 2001, "Truly selective refinement of progressive meshes" (fundamental cut vertices, the
//     dual view: every face of a selectively refined mesh is an input face with corners mapped to their
//     active ancestors, so vsplit/ecol need no other vertex to be split or collapsed first);
//   Kim, Lee & Kobbelt 2005, "View-dependent streaming of progressive meshes" §4–5 (ActiveAncestor on
//     <tree-id, node-id> ids with only part of the hierarchy known; the partial order of SelStreamVSplit
//     when ActiveAncestor(v̂_l) == ActiveAncestor(v̂_r));
//   Hoppe 1997 (vsplit / ecol); Dey et al. 1999 (link condition for collapses).
// Fan order and v_t / v_u roles follow docs/internals.md. Layout: faces are corner triples that keep their
// index while their corners move; each active vertex lists its incident faces in a pooled block, and an
// operation reads those lists into small scratch arrays (one cache line per fan, not a chain of
// dependent twin lookups), works there, and writes back.
#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstring>
#include <iterator>

#include "common/error.h"
#include "spm/selective_mesh.h"
#include "spm/slot_growth.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

constexpr const char* kWhere = "selective mesh";
constexpr uint32_t kMinPoolCapacity = 16;
constexpr uint32_t kMaxFanCapacity = 1u << 30;
constexpr uint32_t kScannedFan = 16;  // find_next: longer fans are sorted and bisected
constexpr uint32_t kSplitFan = 64;    // split_between's fans (on the stack); longer ones take split_fan
constexpr uint32_t kNextCorner[3] = {1, 2, 0}, kPrevCorner[3] = {2, 0, 1};

}  // namespace

SelectiveMesh::SelectiveMesh(const VertexHierarchy& hierarchy, std::span<const uint32_t> base_faces)
    : hierarchy_(&hierarchy) {
  std::fill(std::begin(free_block_), std::end(free_block_), kNone);
  if (base_faces.size() % 3 != 0) fail("base mesh", "face array length is not a multiple of 3");
  if (base_faces.size() >= kNone) fail("base mesh", "too many faces");
  const uint32_t corners = uint32_t(base_faces.size());
  corner_.resize(corners);
  partner_.assign(corners / 3, kNone);
  face_count_ = base_face_count_ = corners / 3;
  for (uint32_t c = 0; c < corners; ++c) {
    if (base_faces[c] >= hierarchy.root_count())
      fail("base mesh", "face " + std::to_string(c / 3) + " uses unknown root " + std::to_string(base_faces[c]));
    corner_[c] = hierarchy.root_slot(base_faces[c]);
  }
  for (uint32_t c = 0; c < corners; ++c)
    if (corner_[c] == corner_[c - c % 3 + kNextCorner[c % 3]])
      fail("base mesh", "face " + std::to_string(c / 3) + " is degenerate");
  reserve_faces();
  uint32_t root_end = 0;
  for (uint32_t r = 0; r < hierarchy.root_count(); ++r) root_end = std::max(root_end, hierarchy.root_slot(r) + 1);
  grow_records(root_end);
  std::vector<uint32_t> count(root_end, 0);
  for (uint32_t c = 0; c < corners; ++c) ++count[corner_[c]];
  for (uint32_t r = 0; r < hierarchy.root_count(); ++r) {
    const uint32_t slot = hierarchy.root_slot(r);
    if (count[slot] == 0) fail("base mesh", "root " + to_string(hierarchy.id(slot)) + " has no face");
    assign_faces(slot, count[slot]);
  }
  for (uint32_t c = 0; c < corners; ++c) {
    const uint32_t v = corner_[c];
    faces_of(vertex_[v])[--count[v]] = c / 3;
  }
  for (uint32_t r = 0; r < hierarchy.root_count(); ++r) {
    const uint32_t slot = hierarchy.root_slot(r);
    if (repeats_directed_edge(slot))
      fail("base mesh", "root " + to_string(hierarchy.id(slot)) +
                            ": edge used twice in the same direction (non-manifold or inconsistent orientation)");
    put_in_fan_order(slot);
    if (ordered_.size() != fan_.size())
      fail("base mesh", "root " + to_string(hierarchy.id(slot)) + " is non-manifold (its faces form several fans)");
  }
  active_.reserve(hierarchy.root_count());
  for (uint32_t r = 0; r < hierarchy.root_count(); ++r)
    activate(hierarchy.root_slot(r), hierarchy.id(hierarchy.root_slot(r)));
}

// The prefetch helpers are always inlined: GCC deems a function that only prefetches free of side
// effects and deletes calls to it (as a plain call this prefetched nothing). Each reads only what an
// earlier stage brought in, and checks bounds: a slot's state may have changed since.
[[gnu::always_inline]] inline void SelectiveMesh::prefetch_record(uint32_t v) const {
  if (v < vertex_.size()) __builtin_prefetch(&vertex_[v]);
}

// One stage over v's fan (long fans are rare and skipped): its faces' corners; or, those in cache, the
// records a split reads (every neighbour's: the cut vertices' active ancestors are among them); or those
// a collapse into v's sibling u reads (the apexes of the faces on edge v-u, and the partners of faces
// with apex v, for breaks_split_order).
[[gnu::always_inline]] inline void SelectiveMesh::prefetch_fan(uint32_t v, FanStage stage) const {
  if (!is_active(v)) return;  // an inactive record holds stale bytes
  const VertexRecord& record = vertex_[v];
  if (record.capacity > kInlineFaces) return;
  for (uint32_t i = 0; i < record.size; ++i) {
    const uint32_t face = record.inline_faces[i];
    const uint32_t* corner = &corner_[3 * size_t(face)];
    if (stage == FanStage::corners) {
      __builtin_prefetch(corner);
      continue;
    }
    const uint32_t k = uint32_t(corner[1] == v) + 2 * uint32_t(corner[2] == v);
    const uint32_t next = corner[kNextCorner[k]], prev = corner[kPrevCorner[k]];
    if (stage == FanStage::split_neighbours) {
      prefetch_record(next);  // each neighbour is the corner after v in one face (but an open fan's far end)
      continue;
    }
    const uint32_t u = v + 1;
    if (next == u) prefetch_record(prev);
    if (prev == u) prefetch_record(next);
    if (k == 2) __builtin_prefetch(&partner_[face]);
  }
}

void SelectiveMesh::prefetch_vsplit(uint32_t s, int stage) const {
  const VertexHierarchy& h = *hierarchy_;
  if (s >= vertex_.size() || s >= h.size()) return;
  switch (stage) {
    case 0:
      __builtin_prefetch(h.first_child_address(s));
      prefetch_record(s);
      break;
    case 1:
      if (const uint32_t t = h.first_child(s); t != kNone) {
        prefetch_record(t);  // written by the split
        prefetch_record(t + 1);
        __builtin_prefetch(h.cut_address(t));
      }
      prefetch_fan(s, FanStage::corners);
      break;
    case 2:
      prefetch_fan(s, FanStage::split_neighbours);
      break;
    default:
      break;
  }
}

void SelectiveMesh::prefetch_ecol(uint32_t p, int stage) const {
  const VertexHierarchy& h = *hierarchy_;
  if (p >= h.size()) return;
  if (stage == 0) {
    __builtin_prefetch(h.first_child_address(p));
    return;
  }
  const uint32_t t = h.first_child(p);
  if (t == kNone || t + 1 >= vertex_.size()) return;
  switch (stage) {
    case 1:
      prefetch_record(t);
      prefetch_record(t + 1);
      __builtin_prefetch(h.cut_address(t));
      break;
    case 2:
      prefetch_fan(t, FanStage::corners);
      prefetch_fan(t + 1, FanStage::corners);
      break;
    case 3:
      prefetch_fan(t, FanStage::collapse_reads);
      break;
    default:
      break;
  }
}

// Each known split adds at most two faces: room for all of them, so no split reallocates the face
// arrays (growing geometrically, as the hierarchy grows a packet at a time). Only reserved: memory is
// touched as faces are made.
void SelectiveMesh::reserve_new_faces() {
  const VertexHierarchy& h = *hierarchy_;
  reserved_for_ = h.size();
  const size_t face_bound = base_face_count_ + (h.size() - h.root_count());
  if (3 * face_bound > corner_.capacity()) {
    const size_t faces = std::max(face_bound, corner_.capacity() / 3 * 2);
    corner_.reserve(3 * faces);
    partner_.reserve(faces);
  }
}

void SelectiveMesh::add_records(uint32_t end) {
  const size_t known = hierarchy_->size();
  vertex_.grow(end, known);
  active_bits_.resize((vertex_.size() + 63) / 64, 0);
}

// Lists longer than kInlineFaces live in pool blocks of power-of-two sizes, recycled per size: a list
// moves only when it outgrows its block, and split/collapse mostly reuse the block just freed.
uint32_t SelectiveMesh::alloc_block(uint32_t capacity) {
  const int size_class = std::countr_zero(capacity);
  if (const uint32_t begin = free_block_[size_class]; begin != kNone) {
    free_block_[size_class] = pool_[begin];
    return begin;
  }
  if (pool_.size() + capacity >= kNone) fail(kWhere, "too many incident faces");
  const uint32_t begin = uint32_t(pool_.size());
  pool_.resize(pool_.size() + capacity);
  return begin;
}

void SelectiveMesh::free_block(uint32_t begin, uint32_t capacity) {
  const int size_class = std::countr_zero(capacity);
  pool_[begin] = free_block_[size_class];
  free_block_[size_class] = begin;
}

[[gnu::always_inline]] inline uint32_t* SelectiveMesh::assign_faces(uint32_t v, uint32_t count) {
  if (count > kMaxFanCapacity) fail(kWhere, "vertex " + to_string(hierarchy_->id(v)) + " has too many faces");
  VertexRecord& record = vertex_[v];
  record.size = count;
  record.capacity = kInlineFaces;
  if (count > kInlineFaces) {
    record.capacity = std::bit_ceil(std::max(count, kMinPoolCapacity));
    record.inline_faces[0] = alloc_block(record.capacity);
  }
  return faces_of(record);
}

void SelectiveMesh::append_face(uint32_t v, uint32_t f) {
  VertexRecord& record = vertex_[v];
  if (record.size == record.capacity) {  // full: move to the next larger pool block
    if (record.capacity >= kMaxFanCapacity)
      fail(kWhere, "vertex " + to_string(hierarchy_->id(v)) + " has too many faces");
    const uint32_t capacity = std::bit_ceil(std::max(record.capacity + 1, kMinPoolCapacity));  // a size class
    const uint32_t begin = alloc_block(capacity);  // may move pool_: read the old list after it
    std::copy_n(faces_of(record), record.size, pool_.begin() + begin);
    if (record.capacity > kInlineFaces) free_block(record.inline_faces[0], record.capacity);
    record.inline_faces[0] = begin;
    record.capacity = capacity;
  }
  faces_of(record)[record.size++] = f;
}

// Inserts f next to `anchor` in an inline list with room for it, without branches: where the anchor
// lies varies from split to split, and a shifting loop that stops there mispredicted its exit. Ten
// entries as three 4-lane vectors (lanes 0-3, 4-7, 6-9; the last two overlap and get the same values);
// each lane takes its own entry, the one before it (shifted) or f. The lane before entry 0 is read from
// the record's bytes and never taken. Returns false, changing nothing, when the anchor is not listed.
[[gnu::always_inline]] inline bool SelectiveMesh::insert_inline_face(VertexRecord& record, uint32_t f, uint32_t anchor,
                                                                     bool after) {
  using Lanes = int32_t __attribute__((vector_size(16)));  // signed: SSE2 compares signed lanes only
  static_assert(kInlineFaces == 10 && offsetof(VertexRecord, inline_faces) >= sizeof(uint32_t));
  unsigned char* const bytes = reinterpret_cast<unsigned char*>(&record) + offsetof(VertexRecord, inline_faces);
  const auto load = [&](int entry) {
    Lanes lanes;
    std::memcpy(&lanes, bytes + 4 * entry, sizeof lanes);
    return lanes;
  };
  constexpr int kFirst[3] = {0, 4, 6};
  const Lanes index[3] = {Lanes{0, 1, 2, 3}, Lanes{4, 5, 6, 7}, Lanes{6, 7, 8, 9}};
  const Lanes own[3] = {Lanes{-1, -1, -1, -1}, Lanes{-1, -1, -1, -1}, Lanes{0, 0, -1, -1}};  // lanes 6, 7 once
  const int32_t size = int32_t(record.size), key = int32_t(anchor), face = int32_t(f);
  Lanes found = {0, 0, 0, 0};  // 1 + the anchor's index in its lane, 0 elsewhere
  for (int part = 0; part < 3; ++part)
    found += (index[part] + 1) & (load(kFirst[part]) == key) & (index[part] < size) & own[part];
  const int32_t place = found[0] + found[1] + found[2] + found[3];
  if (place == 0) return false;
  const int32_t at = place - 1 + int32_t(after);  // f's index; what was there and after moves up one
  Lanes out[3];
  for (int part = 0; part < 3; ++part) {
    const Lanes moves = index[part] > at, lands = index[part] == at;
    out[part] = (load(kFirst[part] - 1) & moves) | (load(kFirst[part]) & ~(moves | lands)) | (face & lands);
  }
  for (int part = 0; part < 3; ++part) std::memcpy(bytes + 4 * kFirst[part], &out[part], sizeof out[part]);
  ++record.size;
  return true;
}

[[gnu::always_inline]] inline void SelectiveMesh::insert_face(uint32_t v, uint32_t f, uint32_t anchor, bool after) {
  VertexRecord& record = vertex_[v];
  if (record.capacity == kInlineFaces && record.size < kInlineFaces) {
    if (!insert_inline_face(record, f, anchor, after))
      fail(kWhere, "face list of " + to_string(hierarchy_->id(v)) + " lacks face " + std::to_string(anchor));
    return;
  }
  if (record.size == record.capacity) append_face(v, f);  // moves the list to a larger block; f is overwritten
  else ++record.size;
  uint32_t* list = faces_of(record);
  uint32_t i = record.size - 1;
  for (; i > 0 && list[i - 1] != anchor; --i) list[i] = list[i - 1];  // shifts what follows the anchor
  if (i == 0) fail(kWhere, "face list of " + to_string(hierarchy_->id(v)) + " lacks face " + std::to_string(anchor));
  if (!after) {
    list[i] = anchor;
    --i;
  }
  list[i] = f;
}

void SelectiveMesh::remove_face(uint32_t v, uint32_t f) {
  VertexRecord& record = vertex_[v];
  uint32_t* list = faces_of(record);
  uint32_t i = 0;
  while (i < record.size && list[i] != f) ++i;
  if (i == record.size)
    fail(kWhere, "face list of " + to_string(hierarchy_->id(v)) + " lacks face " + std::to_string(f));
  std::copy(list + i + 1, list + record.size, list + i);
  --record.size;
}

[[gnu::always_inline]] inline void SelectiveMesh::activate(uint32_t v, VertexId id) {
  VertexRecord& record = vertex_[v];
  record.tree = id.tree;
  record.node = id.node;
  record.active_pos = uint32_t(active_.size());
  active_.push_back(v);
  active_bits_[v >> 6] |= uint64_t(1) << (v & 63);
  ++changes_;
}

[[gnu::always_inline]] inline void SelectiveMesh::deactivate(uint32_t v) {
  VertexRecord& record = vertex_[v];
  active_[record.active_pos] = active_.back();
  vertex_[active_.back()].active_pos = record.active_pos;
  active_.pop_back();
  if (record.capacity > kInlineFaces) free_block(record.inline_faces[0], record.capacity);
  record.size = record.capacity = 0;
  record.active_pos = kNone;
  active_bits_[v >> 6] &= ~(uint64_t(1) << (v & 63));
  ++changes_;
}

[[gnu::always_inline]] inline uint32_t SelectiveMesh::new_face(uint32_t a, uint32_t b, uint32_t c) {
  if (free_face_ == kNone) [[unlikely]]
    add_free_faces();
  const uint32_t f = free_face_;
  free_face_ = corner_[3 * size_t(f) + 1];
  uint32_t* corner = &corner_[3 * size_t(f)];
  corner[0] = a;
  corner[1] = b;
  corner[2] = c;
  partner_[f] = kNone;
  ++face_count_;
  return f;
}

// Appends a batch of dead faces to the free list, first at its head, so faces are taken in index order
// as if appended one by one; new_face stays one path, small enough to inline where it is called.
void SelectiveMesh::add_free_faces() {
  constexpr uint32_t kBatch = 64;
  const uint32_t first = face_capacity();
  const uint32_t count = std::min<uint64_t>(kBatch, (uint64_t(kNone) - 1 - corner_.size()) / 3);
  if (count == 0) fail(kWhere, "too many faces");
  corner_.resize(corner_.size() + 3 * size_t(count));
  partner_.resize(partner_.size() + count, kNone);
  for (uint32_t i = 0; i < count; ++i) {
    corner_[3 * size_t(first + i)] = kNone;
    corner_[3 * size_t(first + i) + 1] = i + 1 < count ? first + i + 1 : kNone;
  }
  free_face_ = first;
}

void SelectiveMesh::free_face(uint32_t f) {
  corner_[3 * size_t(f)] = kNone;
  corner_[3 * size_t(f) + 1] = free_face_;
  partner_[f] = kNone;
  free_face_ = f;
  --face_count_;
}

void SelectiveMesh::load_corners(uint32_t v, std::vector<Corner>& corners) const {
  const VertexRecord& record = vertex_[v];
  const uint32_t n = record.size;  // locals: the stores below could alias the record
  corners.resize(n);
  const uint32_t* list = faces_of(record);
  const uint32_t* corner = corner_.data();
  Corner* out = corners.data();
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t face = list[i];
    const uint32_t* c = corner + 3 * size_t(face);
    const uint32_t k = uint32_t(c[1] == v) + 2 * uint32_t(c[2] == v);  // branch-free: c was a cache miss
    out[i] = {face, k, c[kNextCorner[k]], c[kPrevCorner[k]]};
  }
}

// Corner lookups by `next`: directed edges v -> a are unique in a manifold, so `next` is a key. Fans
// are short (5-7 faces), where a scan beats sorting; a long one (a coarse base mesh) is sorted by
// prepare_lookup and searched by halves, so no fan costs quadratic time.
void SelectiveMesh::prepare_lookup(std::vector<Corner>& fan) {
  if (fan.size() > kScannedFan)
    std::sort(fan.begin(), fan.end(), [](const Corner& a, const Corner& b) { return a.next < b.next; });
}

[[gnu::always_inline]] inline uint32_t SelectiveMesh::find_next(const std::vector<Corner>& fan, uint32_t w) {
  const uint32_t n = uint32_t(fan.size());
  if (n <= kScannedFan) {
    // Every corner compared, no early exit: where the match lies is data, and a mispredicted exit
    // cost more than the few compares it saved.
    uint32_t match = 0;
    for (uint32_t i = 0; i < n; ++i) match |= uint32_t(fan[i].next == w) << i;
    return match != 0 ? uint32_t(std::countr_zero(match)) : kNone;
  }
  const auto it = std::lower_bound(fan.begin(), fan.end(), w, [](const Corner& c, uint32_t x) { return c.next < x; });
  return it != fan.end() && it->next == w ? uint32_t(it - fan.begin()) : kNone;
}

// Puts a vertex's corners (`fan`, any order) in CCW fan order into `ordered`: face (v, a, b) is followed
// by (v, b, c), and an open fan starts after its gap. Returns whether the fan is closed. When the faces
// form several fans (a bad base mesh), `ordered` ends up shorter than `fan`.
bool SelectiveMesh::order_fan(std::vector<Corner>& fan, std::vector<Corner>& ordered,
                              std::vector<uint32_t>& successor) {
  const uint32_t n = uint32_t(fan.size());
  prepare_lookup(fan);
  successor.resize(n);
  uint64_t reached = 0;  // sum of the indices some corner leads to
  uint32_t ends = 0;
  for (uint32_t i = 0; i < n; ++i) {
    successor[i] = find_next(fan, fan[i].prev);
    if (successor[i] == kNone) ++ends;
    else reached += successor[i];
  }
  // One open fan has one last face and one first face, the only index nothing leads to.
  const uint64_t first = ends == 0 ? 0 : uint64_t(n) * (n - 1) / 2 - reached;
  ordered.clear();
  if (ends > 1 || first >= n) return false;
  for (uint32_t i = uint32_t(first); i != kNone && ordered.size() < n; i = successor[i]) ordered.push_back(fan[i]);
  return ends == 0;
}

// A directed edge v -> w of two faces shows as two of v's corners with the same `next`. Checked per
// fan, where a fan's few corners are compared pairwise (a long one sorted), instead of sorting every
// edge of the base mesh: a fresh mesh pays this on each construction.
bool SelectiveMesh::repeats_directed_edge(uint32_t v) {
  load_corners(v, fan_);
  prepare_lookup(fan_);
  const size_t n = fan_.size();
  if (n > kScannedFan) {
    for (size_t i = 1; i < n; ++i)
      if (fan_[i - 1].next == fan_[i].next) return true;
    return false;
  }
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      if (fan_[i].next == fan_[j].next) return true;
  return false;
}

// Reads v's corners, orders them and writes the order back: for lists the fast paths of vsplit and ecol
// do not keep in order (a side on the border, long fans), and the base mesh. Leaves the order in
// ordered_ (shorter than fan_ when the faces form several fans; the list is then left as it was).
void SelectiveMesh::put_in_fan_order(uint32_t v) {
  load_corners(v, fan_);
  order_fan(fan_, ordered_, successor_);
  if (ordered_.size() != fan_.size()) return;
  uint32_t* list = faces_of(vertex_[v]);
  for (const Corner& c : ordered_) *list++ = c.face;
}

// Turns v's list, in cyclic fan order, so that an open fan starts after its gap.
void SelectiveMesh::start_after_gap(uint32_t v) {
  load_corners(v, fan_);
  const uint32_t n = uint32_t(fan_.size());
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t next = i + 1 == n ? 0 : i + 1;
    if (fan_[i].prev == fan_[next].next) continue;
    uint32_t* list = faces_of(vertex_[v]);
    std::rotate(list, list + next, list + n);
    return;
  }
}

uint32_t SelectiveMesh::open_end(std::vector<Corner>& fan) {
  prepare_lookup(fan);
  // One fan is closed exactly when its `next` and `prev` corners are the same set; an open one has one
  // of each unmatched, and they differ (the fan's two ends), so the sums tell without a lookup.
  uint64_t nexts = 0, prevs = 0;
  for (const Corner& c : fan) nexts += c.next, prevs += c.prev;
  if (nexts == prevs) return kNone;
  uint32_t end = kNone;
  for (const Corner& c : fan)
    if (find_next(fan, c.prev) == kNone) end = c.prev;
  return end;
}

// ActiveAncestor by the <tree-id, node-id> path (kim-lee-kobbelt §4). The right-shift climb from v
// meets the same node; walking down from the root reads v's bits instead, so it costs one array step per
// level and no hash lookup, and stops at the first active node since the front crosses the path once.
uint32_t SelectiveMesh::active_ancestor(VertexId v) const {
  if (!is_vertex(v) || v.tree >= hierarchy_->root_count()) return kNone;
  uint32_t slot = hierarchy_->root_slot(v.tree);
  const int depth = v.depth();
  for (int level = 1;; ++level) {
    if (is_active(slot)) return slot;
    const uint32_t child = hierarchy_->first_child(slot);
    if (level > depth || child == kNone) return kNone;
    slot = child + uint32_t((v.node >> (depth - level)) & 1);
  }
}

// ActiveAncestor of the two cut vertices of `slot` (kNone for a missing side), whose corners fan_
// holds. When the packets agree with the mesh each answer is a neighbour of v_s (it becomes an apex of
// f_l or f_r), and an active vertex whose id is a prefix of the cut's is its only active ancestor; so
// one id per neighbour, read once for both cuts, replaces the walk down from the root (one dependent load
// per level). The walk remains for the rest: the forced chain (v_l == v_r need not be adjacent to v_s)
// and the error.
std::pair<uint32_t, uint32_t> SelectiveMesh::cut_ancestors(VertexId cut_l, VertexId cut_r, uint32_t slot) const {
  const VertexId cuts[2] = {cut_l, cut_r};
  uint32_t found[2] = {kNone, kNone};
  int depth[2] = {0, 0};
  uint32_t wanted = 0;  // bit i: cut i still looked for
  for (int i = 0; i < 2; ++i) {
    if (!is_vertex(cuts[i])) continue;
    wanted |= 1u << i;
    depth[i] = cuts[i].depth();
  }
  const auto look = [&](uint32_t v) {
    const VertexRecord& record = vertex_[v];
    const int d = 63 - __builtin_clzll(record.node);  // an active id is never 0
    for (int i = 0; i < 2; ++i) {
      if ((wanted >> i & 1) && record.tree == cuts[i].tree && d <= depth[i] &&
          (cuts[i].node >> (depth[i] - d)) == record.node) {
        found[i] = v;
        wanted &= ~(1u << i);
      }
    }
  };
  for (uint32_t i = 0; wanted != 0 && i < fan_.size(); ++i) look(fan_[i].next);
  for (uint32_t i = 0; wanted != 0 && i < fan_.size(); ++i) look(fan_[i].prev);  // an open fan's far end
  for (int i = 0; i < 2; ++i) {
    if ((wanted >> i & 1) == 0) continue;
    found[i] = active_ancestor(cuts[i]);
    if (found[i] == kNone)
      fail(kWhere,
           "vertex " + to_string(hierarchy_->id(slot)) + ": no active ancestor for cut vertex " + to_string(cuts[i]));
  }
  return {found[0], found[1]};
}

// The fan split of docs/internals.md: v_s's faces from (v_s, v_l, ·) CCW to (v_s, ·, v_r) go to v_t,
// the rest to v_u; f_l = (t, u, l) and f_r = (u, t, r) fill the gap. On an open fan a side may lie on
// the boundary: with no face (v_s, v_l, ·) (edge t-l was a border) v_t's faces start at the beginning of
// the fan, with no face (v_s, ·, v_r) they run to its end, and with neither (or a one-sided split whose
// only side is a border) v_t keeps only the new faces. Everything is checked before the first write,
// so inconsistent packets leave the mesh as it was.
void SelectiveMesh::split_fan(uint32_t s, uint32_t l, uint32_t r) {  // fan_: s's corners
  const uint32_t t = hierarchy_->first_child(s), u = t + 1;
  const auto reject = [&](const std::string& why) {
    fail(kWhere, "vsplit " + to_string(hierarchy_->id(s)) + ": " + why);
  };
  const bool closed = order_fan(fan_, ordered_, successor_);
  if (ordered_.size() != fan_.size()) reject("corrupted fan");
  const uint32_t n = uint32_t(ordered_.size());
  // ia / ib: fan positions of the faces (s, l, ·) and (s, ·, r), kNone on a border.
  uint32_t ia = kNone, ib = kNone;
  bool l_found = false, r_found = false;
  for (uint32_t i = 0; i < n; ++i) {
    const Corner& c = ordered_[i];
    if (c.next == l) ia = i;
    if (c.prev == r) ib = i;
    l_found |= c.next == l || c.prev == l;
    r_found |= c.next == r || c.prev == r;
  }
  for (auto [v, found] : {std::pair{l, l_found}, std::pair{r, r_found}})
    if (v != kNone && !found) reject("cut vertex " + to_string(hierarchy_->id(v)) + " is not a neighbour");
  if ((l == kNone || r == kNone || (ia == kNone && ib == kNone)) && closed)
    reject("boundary split of an interior vertex");

  // v_t's faces: the cyclic range [first, last] of the ordered fan (empty when neither side is found).
  const bool any = ia != kNone || ib != kNone;
  const uint32_t first = ia != kNone ? ia : 0, last = ib != kNone ? ib : n - 1;
  const uint32_t t_count = !any ? 0 : first <= last ? last - first + 1 : n - first + last + 1;
  const uint32_t fl = l != kNone ? new_face(t, u, l) : kNone;
  const uint32_t fr = r != kNone ? new_face(u, t, r) : kNone;
  if (fl != kNone && fr != kNone) {
    partner_[fl] = fr;
    partner_[fr] = fl;
  }
  const uint32_t added = (fl != kNone) + (fr != kNone);
  const VertexId id = id_of(s);
  deactivate(s);
  // Each child's faces in cyclic fan order, its new faces after its range (v_t: f_r, f_l; v_u: f_l,
  // f_r), with gaps where faces are missing; start_after_gap then turns each list to its gap.
  for (uint32_t child : {t, u}) {
    const uint32_t count = child == t ? t_count : n - t_count, begin = child == t ? first : (first + t_count) % n;
    uint32_t* list = assign_faces(child, count + added);
    for (uint32_t j = 0, i = begin; j < count; ++j, i = i + 1 == n ? 0 : i + 1) {
      corner_[3 * size_t(ordered_[i].face) + ordered_[i].k] = child;
      *list++ = ordered_[i].face;
    }
    for (uint32_t f : child == t ? std::array{fr, fl} : std::array{fl, fr})
      if (f != kNone) *list++ = f;
  }
  // Around v_l, f_l = (l, t, u) comes after (l, ·, t) = (s, l, ·), else before (l, u, ·) = (s, ·, l);
  // around v_r, f_r = (r, u, t) before (r, t, ·) = (s, ·, r), else after (r, ·, u) = (s, r, ·).
  const auto face_where = [&](bool use_next, uint32_t w) {
    for (const Corner& c : ordered_)
      if ((use_next ? c.next : c.prev) == w) return c.face;
    return kNone;
  };
  if (fl != kNone) {
    if (ia != kNone) insert_face(l, fl, ordered_[ia].face, true);
    else insert_face(l, fl, face_where(false, l), false);
  }
  if (fr != kNone) {
    if (ib != kNone) insert_face(r, fr, ordered_[ib].face, false);
    else insert_face(r, fr, face_where(true, r), true);
  }
  activate(t, id.child(0));
  activate(u, id.child(1));
  start_after_gap(t);
  start_after_gap(u);
}

// vsplit's common case in one pass over v_s's fan: both cut vertices have their active ancestors v_l
// and v_r among v_s's neighbours, as the `next` corners of faces (s, l, ·) at ia and (s, r, ·) at jr
// (an active vertex whose id is a prefix of the cut's is its only active ancestor). s's list is in fan
// order, an open fan from the face after its gap, so (s, ·, r) is the face before jr, and v_t's faces,
// (s, l, ·) CCW up to (s, ·, r), are one cyclic range [ia, ib] of the list and v_u's the rest; f_r and
// f_l go where the ranges end, which keeps both children's lists in fan order (the range that wraps
// round the list's end holds the gap of an open fan, and stays split there). A one-sided split goes on
// to split_one_side. Returns false, having changed nothing, for the rest: a side on the border,
// v_l == v_r (the forced chain), a long fan; split_fan's general path reads the fan again for those.
bool SelectiveMesh::split_between(uint32_t s, VertexId cut_l, VertexId cut_r) {
  const VertexRecord& record = vertex_[s];
  const uint32_t n = record.size;
  const bool has_l = is_vertex(cut_l), has_r = is_vertex(cut_r);
  if (n > kSplitFan || n == 0 || !(has_l || has_r)) return false;
  constexpr VertexId kNoMatch{kNone, 1};  // no active vertex's id: the missing side of a one-sided split
  if (!has_l) cut_l = kNoMatch;
  if (!has_r) cut_r = kNoMatch;
  const uint32_t* face = faces_of(record);
  uint32_t copied[kSplitFan], k[kSplitFan], next[kSplitFan];
  if (record.capacity > kInlineFaces) {  // deactivate() frees the pool block, and the children may take it
    std::copy_n(face, n, copied);
    face = copied;
  }
  static_assert(kSplitFan <= 64);
  // v is an ancestor of (or is) the cut when the cut's id shifted to v's depth is v's; depths as leading
  // zeros, so `up` wraps past 63 when v lies deeper than the cut. Branch-free, with one bit per neighbour
  // for each cut: which neighbour matches depends on the view, so a branch here mispredicts, and two
  // bit masks leave the loop few enough live values to stay in registers.
  const int zeros_l = __builtin_clzll(cut_l.node), zeros_r = __builtin_clzll(cut_r.node);
  const auto below = [](const VertexRecord& v, int zeros, VertexId cut, int cut_zeros) {
    const uint32_t up = uint32_t(zeros - cut_zeros);
    return uint64_t((((cut.node >> (up & 63)) ^ v.node) | (cut.tree ^ v.tree) | (up >> 6)) == 0);
  };
  uint64_t match_l = 0, match_r = 0;  // bit i: neighbour i is v_l's (v_r's) active ancestor
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t* c = &corner_[3 * size_t(face[i])];
    k[i] = uint32_t(c[1] == s) + 2 * uint32_t(c[2] == s);
    next[i] = c[kNextCorner[k[i]]];
    const VertexRecord& w = vertex_[next[i]];
    const int zeros = __builtin_clzll(w.node);  // an active id is never 0
    match_l |= below(w, zeros, cut_l, zeros_l) << i;
    match_r |= below(w, zeros, cut_r, zeros_r) << i;
  }
  if (!(has_l && has_r)) return split_one_side(s, {face, k, next, n}, has_l ? match_l : match_r, has_l);
  if (match_l == 0 || match_r == 0) return false;
  const uint32_t ia = uint32_t(std::countr_zero(match_l)), jr = uint32_t(std::countr_zero(match_r));
  if (ia == jr) return false;
  const uint32_t l = next[ia], r = next[jr];
  const uint32_t ib = jr > 0 ? jr - 1 : n - 1;
  if (jr == 0 && corner_[3 * size_t(face[ib]) + kPrevCorner[k[ib]]] != r) return false;  // no (s, ·, r): the border
  const uint32_t t = hierarchy_->first_child(s), u = t + 1;
  const uint32_t fl = new_face(t, u, l), fr = new_face(u, t, r);
  partner_[fl] = fr;
  partner_[fr] = fl;
  const VertexId id = id_of(s);
  deactivate(s);
  // v_t takes faces ia … ib (cyclically), v_u the rest; each list keeps the fan's order with the two new
  // faces where the fan was cut: t: [ia … ib] fr fl, u: [ib+1 … ia−1] fl fr, each rotated as the old
  // list was (an open fan starts after its gap).
  // Whether v_t's range runs over the list's end varies with the view: the choices below are masks, as
  // branches they mispredicted.
  const bool wraps = ia > ib;
  const uint32_t wrap_mask = 0 - uint32_t(wraps);
  const auto pick = [wrap_mask](uint32_t if_wraps, uint32_t otherwise) {
    return otherwise ^ ((if_wraps ^ otherwise) & wrap_mask);
  };
  const uint32_t t_count = ib - ia + 1 + (n & wrap_mask);
  assign_faces(t, t_count + 2);  // may move pool_: the lists are read once both are assigned
  assign_faces(u, n - t_count + 2);
  uint32_t* const lists[2] = {faces_of(vertex_[u]), faces_of(vertex_[t])};
  // Face i goes to i − shift in its child's list, one shift before the new faces' place and one after
  // (unsigned: a shift may be "negative"). One loop without branches: separate loops over the ranges,
  // whose lengths are the view's, each mispredicted its exit.
  const uint32_t gap[2] = {pick(n, ia), pick(ib + 1, n)};
  const uint32_t shift[2][2] = {{t_count - 2, pick(ib + 1, 0)}, {ia - ib - 3, pick(0, ia)}};
  const uint32_t child[2] = {u, t}, lo = pick(ib + 1, ia), hi = pick(ia, ib + 1);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t to_t = uint32_t((i >= lo) & (i < hi)) ^ uint32_t(wraps);
    lists[to_t][i - shift[to_t][i < gap[to_t]]] = face[i];
    corner_[3 * size_t(face[i]) + k[i]] = child[to_t];
  }
  lists[1][pick(ib + 1, t_count)] = fr;
  lists[1][pick(ib + 2, t_count + 1)] = fl;
  lists[0][pick(n - t_count, ia)] = fl;
  lists[0][pick(n - t_count + 1, ia + 1)] = fr;
  // Around v_l, f_l = (l, t, u) follows (l, ·, t), which was (s, l, ·); around v_r, f_r = (r, u, t)
  // comes before (r, t, ·), which was (s, ·, r).
  insert_face(l, fl, face[ia], true);
  insert_face(r, fr, face[ib], false);
  activate(t, id.child(0));
  activate(u, id.child(1));
  return true;
}

// split_between's one-sided split (v_s on the border, one cut missing), on an open fan listed from the
// face after its gap: split_fan's result without ordering the fan. With v_l present, v_t takes the faces
// from (s, l, ·) at p to the fan's end and v_u those before, f_l = (t, u, l) between them; with v_r
// present, v_t takes those up to (s, ·, r) at p − 1 and v_u the rest, f_r = (u, t, r) between them.
// Returns false, having changed nothing, for the side's neighbour at the fan's start and a closed fan.
// Out of line: it is rare, and split_between's common case is what must stay small.
[[gnu::noinline]] bool SelectiveMesh::split_one_side(uint32_t s, const FanReading& fan, uint64_t match, bool left) {
  const uint32_t n = fan.size;
  if (match == 0) return false;
  const uint32_t p = uint32_t(std::countr_zero(match));
  if (p == 0 || corner_[3 * size_t(fan.face[n - 1]) + kPrevCorner[fan.k[n - 1]]] == fan.next[0]) return false;
  const uint32_t t = hierarchy_->first_child(s), u = t + 1, side = fan.next[p];
  const uint32_t f = left ? new_face(t, u, side) : new_face(u, t, side);
  const VertexId id = id_of(s);
  deactivate(s);
  // Faces before p go to child a, at their places; f ends a's list and starts b's, which has the rest.
  const uint32_t a = left ? u : t, b = left ? t : u;
  assign_faces(a, p + 1);  // may move pool_: the lists are read once both are assigned
  assign_faces(b, n - p + 1);
  uint32_t* const list_a = faces_of(vertex_[a]);
  uint32_t* const list_b = faces_of(vertex_[b]);
  for (uint32_t i = 0; i < p; ++i) {
    list_a[i] = fan.face[i];
    corner_[3 * size_t(fan.face[i]) + fan.k[i]] = a;
  }
  list_a[p] = f;
  list_b[0] = f;
  for (uint32_t i = p; i < n; ++i) {
    list_b[i - p + 1] = fan.face[i];
    corner_[3 * size_t(fan.face[i]) + fan.k[i]] = b;
  }
  // As in split_between: f_l follows (l, ·, t), which was (s, l, ·); f_r comes before (r, t, ·), which
  // was (s, ·, r).
  if (left) insert_face(side, f, fan.face[p], true);
  else insert_face(side, f, fan.face[p - 1], false);
  activate(t, id.child(0));
  activate(u, id.child(1));
  return true;
}

VSplitResult SelectiveMesh::vsplit(uint32_t slot) {
  reserve_faces();
  if (!is_active(slot))
    fail(kWhere, "vsplit of inactive vertex " + (slot < hierarchy_->size() ? to_string(hierarchy_->id(slot)) : "?"));
  uint32_t tried = kNone;  // split_between found no common case for it, and the mesh has not changed since
  if (const uint32_t t = hierarchy_->first_child(slot); t != kNone) {  // the common case: no chain
    grow_records(t + 2);
    if (split_between(slot, hierarchy_->cut_of_child(t), hierarchy_->cut_of_child(t + 1))) return {true, kNone};
    tried = slot;
  }
  // SelStreamVSplit (kim-lee-kobbelt §5.3) without recursion: v_l == v_r must be split first, and that
  // split may in turn wait for another. Every stacked vertex is active and distinct unless the packets
  // are cyclic, which the size bound catches.
  chain_.clear();
  chain_.push_back(slot);
  while (!chain_.empty()) {
    const uint32_t s = chain_.back();
    if (!is_active(s)) fail(kWhere, "cyclic split order at " + to_string(hierarchy_->id(s)));
    const uint32_t t = hierarchy_->first_child(s);
    if (t == kNone) return {false, s};
    grow_records(t + 2);
    const VertexId cut_l = hierarchy_->cut_of_child(t), cut_r = hierarchy_->cut_of_child(t + 1);
    const bool untried = s != tried;
    tried = kNone;
    if (untried && split_between(s, cut_l, cut_r)) {
      chain_.pop_back();
      continue;
    }
    load_corners(s, fan_);
    const auto [l, r] = cut_ancestors(cut_l, cut_r, s);
    if (l != kNone && l == r) {
      if (chain_.size() > active_.size()) fail(kWhere, "cyclic split order at " + to_string(hierarchy_->id(s)));
      chain_.push_back(l);
      continue;
    }
    split_fan(s, l, r);
    chain_.pop_back();
  }
  return {true, kNone};
}

// Link condition: the common neighbours of t and u are exactly the apexes of the faces on edge t-u;
// any other common neighbour would end up on a doubled edge and pinch the surface.
// Every neighbour of t is some corner's `next` but for the far end of an open fan (`t_end`).
bool SelectiveMesh::link_condition(uint32_t t, uint32_t l, uint32_t r, uint32_t t_end, uint32_t u_end) {
  const auto shared = [&](uint32_t w) {
    return w != t && w != l && w != r && (w == t_end || find_next(fan_, w) != kNone);
  };
  // u's neighbours: each corner's `next`, and an open fan's far end.
  for (const Corner& c : fan_u_)
    if (shared(c.next)) return false;
  return u_end == kNone || !shared(u_end);
}

// The partial order of §5.3 read backwards. A performed split q whose cut vertices have the active
// ancestors t and u would see v_l == v_r once they merge: a front no sequence of vsplits can reach, in
// which q's own collapse is stuck for good. So q's subtree must collapse first. In the dual view the apex
// corner (k = 2) of q's f_l / f_r always holds the active ancestor of v̂_l / v̂_r, and the face of q
// whose apex is t lies in t's fan (fan_): so q shows up as a face there with apex t whose partner's apex
// is u, without reading a single id.
bool SelectiveMesh::breaks_split_order(uint32_t u) const {
  for (const Corner& c : fan_) {
    if (c.k != 2) continue;
    const uint32_t other = partner_[c.face];
    if (other != kNone && corner_[3 * size_t(other) + 2] == u) return true;
  }
  return false;
}

bool SelectiveMesh::ecol(uint32_t p) {
  const VertexHierarchy& h = *hierarchy_;
  if (p >= h.size() || h.first_child(p) == kNone) fail(kWhere, "ecol of a node with no known children");
  const uint32_t t = h.first_child(p), u = t + 1;
  if (!is_active(t) || !is_active(u)) return false;
  load_corners(t, fan_);
  uint32_t fl = kNone, fr = kNone, l = kNone, r = kNone;  // f_l = (t, u, l), f_r = (u, t, r)
  for (const Corner& c : fan_) {
    if (c.next == u) fl = c.face, l = c.prev;
    if (c.prev == u) fr = c.face, r = c.next;
  }
  // The faces on t-u must be those vsplit(p) would create here: same sides, apexes ActiveAncestor(v̂)
  // (an active vertex is the active ancestor of v̂ exactly when its id is a prefix of v̂'s).
  const VertexId cut_l = h.cut_of_child(t), cut_r = h.cut_of_child(u);
  if ((fl != kNone) != is_vertex(cut_l) || (fr != kNone) != is_vertex(cut_r)) return false;
  if (l != kNone && !is_ancestor_or_self(id_of(l), cut_l)) return false;
  if (r != kNone && !is_ancestor_or_self(id_of(r), cut_r)) return false;
  if (l == r) return false;  // both kNone cannot pass the checks above, so l == r means one apex twice
  if (breaks_split_order(u)) return false;
  load_corners(u, fan_u_);
  // Seen with a virtual vertex joined to every border vertex, an interior edge between two border
  // vertices fails the link condition too: merging them would pinch the surface at one vertex.
  const uint32_t t_end = open_end(fan_), u_end = open_end(fan_u_);
  if (fl != kNone && fr != kNone && t_end != kNone && u_end != kNone) return false;
  if (!link_condition(t, l, r, t_end, u_end)) return false;
  // No vertex may be left without faces: an apex whose only face is the one removed, or p itself.
  const uint32_t removed = (fl != kNone) + (fr != kNone);
  const VertexId id = id_of(t).parent();
  const uint32_t count = uint32_t(fan_.size() + fan_u_.size()) - 2 * removed;
  if (count == 0) return false;
  if ((fl != kNone && vertex_[l].size == 1) || (fr != kNone && vertex_[r].size == 1)) return false;

  if (fl != kNone) remove_face(l, fl);
  if (fr != kNone) remove_face(r, fr);
  deactivate(t);
  deactivate(u);
  join_fans(p, fl, fr, t_end != kNone, u_end != kNone);
  if (fl != kNone) free_face(fl);
  if (fr != kNone) free_face(fr);
  activate(p, id);
  return true;
}

// p's list from t's (fan_) and u's (fan_u_) in fan order, f_l and f_r left out: around t, f_r = (t, r,
// u) is followed by f_l = (t, u, l); around u, f_l = (u, l, t) by f_r = (u, t, r); p's fan is t's faces
// after f_l up to f_r, then u's after f_r up to f_l. At most one of t and u is on the border (ecol
// refuses the rest), and p's list starts after that one's gap. A border edge t-u (one new face) or a
// long fan (lookups sort it) takes put_in_fan_order.
void SelectiveMesh::join_fans(uint32_t p, uint32_t fl, uint32_t fr, bool t_open, bool u_open) {
  const uint32_t n = uint32_t(fan_.size()), m = uint32_t(fan_u_.size());
  uint32_t* list = assign_faces(p, n + m - 2 * ((fl != kNone) + (fr != kNone)));  // each is in both fans
  const auto take = [&](const std::vector<Corner>& fan, uint32_t begin, uint32_t count) {
    for (uint32_t i = 0, j = begin; i < count; ++i, j = j + 1 == fan.size() ? 0 : j + 1) {
      corner_[3 * size_t(fan[j].face) + fan[j].k] = p;
      *list++ = fan[j].face;
    }
  };
  uint32_t a = 0, b = 0;  // f_r's place in t's list, f_l's in u's
  while (a < n && fan_[a].face != fr) ++a;
  while (b < m && fan_u_[b].face != fl) ++b;
  // An open list cannot have the pair across its end (that is its gap).
  const bool in_order = fl != kNone && fr != kNone && n <= kScannedFan && m <= kScannedFan && a < n && b < m &&
                        fan_[(a + 1) % n].face == fl && fan_u_[(b + 1) % m].face == fr && !(t_open && a + 1 == n) &&
                        !(u_open && b + 1 == m);
  if (!in_order) {
    for (const std::vector<Corner>* fan : {&fan_, &fan_u_})
      for (uint32_t i = 0; i < fan->size(); ++i)
        if ((*fan)[i].face != fl && (*fan)[i].face != fr) take(*fan, i, 1);
    put_in_fan_order(p);
  } else if (t_open) {  // f_r, f_l lie inside t's list: its gap stays at the end
    take(fan_, 0, a);
    take(fan_u_, (b + 2) % m, m - 2);
    take(fan_, a + 2, n - a - 2);
  } else if (u_open) {
    take(fan_u_, 0, b);
    take(fan_, (a + 2) % n, n - 2);
    take(fan_u_, b + 2, m - b - 2);
  } else {
    take(fan_, (a + 2) % n, n - 2);
    take(fan_u_, (b + 2) % m, m - 2);
  }
}

}  // namespace pms
