// Truly selective refinement over a partial vertex hierarchy:
//   Kim & Lee 2001, "Truly selective refinement of progressive meshes" (fundamental cut vertices, the
//     dual view: every face of a selectively refined mesh is an input face with corners mapped to their
//     active ancestors, so vsplit/ecol need no other vertex to be split or collapsed first);
//   Kim, Lee & Kobbelt 2005, "View-dependent streaming of progressive meshes" §4–5 (ActiveAncestor on
//     <tree-id, node-id> ids with only part of the hierarchy known; the partial order of SelStreamVSplit
//     when ActiveAncestor(v̂_l) == ActiveAncestor(v̂_r));
//   Hoppe 1997 (vsplit / ecol on a half-edge mesh); Dey et al. 1999 (link condition for collapses).
// Fan order and v_t / v_u roles follow docs/internals.md.
#include <algorithm>
#include <bit>

#include "common/error.h"
#include "refine/refine.h"

namespace pms {
namespace {

constexpr const char* kWhere = "selective mesh";
constexpr int kMaxClimb = 3;  // breaks_split_order: parent steps before a hash probe is cheaper

}  // namespace

SelectiveMesh::SelectiveMesh(const VertexHierarchy& hierarchy, std::span<const uint32_t> base_faces)
    : hierarchy_(&hierarchy) {
  if (base_faces.size() % 3 != 0) fail("base mesh", "face array length is not a multiple of 3");
  if (base_faces.size() >= kNone) fail("base mesh", "too many faces");
  const uint32_t half_edges = uint32_t(base_faces.size());
  corner_.resize(half_edges);
  twin_.assign(half_edges, kNone);
  face_count_ = half_edges / 3;
  for (uint32_t h = 0; h < half_edges; ++h) {
    if (base_faces[h] >= hierarchy.root_count())
      fail("base mesh", "face " + std::to_string(h / 3) + " uses unknown root " + std::to_string(base_faces[h]));
    corner_[h] = hierarchy.root_slot(base_faces[h]);
  }
  // Twins by sorting directed edges: a repeated one means a non-manifold edge or flipped neighbours.
  std::vector<std::pair<uint64_t, uint32_t>> edges(half_edges);
  for (uint32_t h = 0; h < half_edges; ++h) {
    if (corner_[h] == head(h)) fail("base mesh", "face " + std::to_string(h / 3) + " is degenerate");
    edges[h] = {uint64_t(corner_[h]) << 32 | head(h), h};
  }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i + 1 < edges.size(); ++i)
    if (edges[i].first == edges[i + 1].first)
      fail("base mesh", "edge used twice in the same direction (non-manifold or inconsistent orientation)");
  for (uint32_t h = 0; h < half_edges; ++h) {
    const uint64_t reverse = uint64_t(head(h)) << 32 | corner_[h];
    auto it = std::lower_bound(edges.begin(), edges.end(), std::pair<uint64_t, uint32_t>{reverse, 0});
    if (it != edges.end() && it->first == reverse) twin_[h] = it->second;
  }
  sync_slots();
  std::vector<uint32_t> corners(hierarchy.size(), 0);
  for (uint32_t h = 0; h < half_edges; ++h) {
    out_[corner_[h]] = h;
    ++corners[corner_[h]];
  }
  for (uint32_t r = 0; r < hierarchy.root_count(); ++r) {
    const uint32_t slot = hierarchy.root_slot(r);
    const std::string name = "root " + to_string(hierarchy.id(slot));
    if (out_[slot] == kNone) fail("base mesh", name + " has no face");
    activate(slot, out_[slot]);
    gather_fan(slot, fan_);
    if (fan_.size() != corners[slot]) fail("base mesh", name + " is non-manifold (its faces form several fans)");
  }
}

void SelectiveMesh::sync_slots() {
  // The hierarchy grows as packets arrive; per-slot arrays follow lazily.
  const size_t n = hierarchy_->size();
  if (out_.size() >= n) return;
  out_.resize(n, kNone);
  active_pos_.resize(n, kNone);
  mark_.resize(n, 0);
}

void SelectiveMesh::activate(uint32_t v, uint32_t out) {
  out_[v] = out;
  active_pos_[v] = uint32_t(active_.size());
  active_.push_back(v);
}

void SelectiveMesh::deactivate(uint32_t v) {
  const uint32_t pos = active_pos_[v];
  active_[pos] = active_.back();
  active_pos_[active_[pos]] = pos;
  active_.pop_back();
  active_pos_[v] = kNone;
  out_[v] = kNone;
}

uint32_t SelectiveMesh::new_face(uint32_t a, uint32_t b, uint32_t c) {
  uint32_t f = free_face_;
  if (f != kNone) {
    free_face_ = corner_[3 * size_t(f) + 1];
  } else {
    if (corner_.size() + 3 >= kNone) fail(kWhere, "too many faces");
    f = face_capacity();
    corner_.resize(corner_.size() + 3);
    twin_.resize(twin_.size() + 3);
  }
  uint32_t* corner = &corner_[3 * size_t(f)];
  corner[0] = a;
  corner[1] = b;
  corner[2] = c;
  std::fill_n(&twin_[3 * size_t(f)], 3, kNone);
  ++face_count_;
  return f;
}

void SelectiveMesh::free_face(uint32_t f) {
  corner_[3 * size_t(f)] = kNone;
  corner_[3 * size_t(f) + 1] = free_face_;
  free_face_ = f;
  --face_count_;
}

void SelectiveMesh::link(uint32_t a, uint32_t b) {
  if (a != kNone) twin_[a] = b;
  if (b != kNone) twin_[b] = a;
}

// Outgoing half-edges of active vertex v in CCW fan order (face (v, a, b) is followed by (v, b, c),
// whose v->b is the twin of b->v); an open fan starts after its gap. Returns whether the fan is closed.
bool SelectiveMesh::gather_fan(uint32_t v, std::vector<uint32_t>& fan) const {
  fan.clear();
  const uint32_t start = out_[v];
  // No fan is longer than the face count: a longer walk means corrupted links, not a slow mesh.
  const size_t limit = face_capacity();
  uint32_t h = start;
  for (;;) {
    fan.push_back(h);
    const uint32_t next = twin_[prev_edge(h)];
    if (next == start) return true;
    if (next == kNone) break;
    if (fan.size() > limit) fail(kWhere, "corrupted fan around " + to_string(hierarchy_->id(v)));
    h = next;
  }
  // Open: collect the part clockwise of `start` and put it in front.
  const size_t ccw = fan.size();
  for (h = start; twin_[h] != kNone;) {
    h = next_edge(twin_[h]);
    fan.push_back(h);
    if (fan.size() > limit) fail(kWhere, "corrupted fan around " + to_string(hierarchy_->id(v)));
  }
  std::reverse(fan.begin() + ccw, fan.end());
  std::rotate(fan.begin(), fan.begin() + ccw, fan.end());
  return false;
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

// ActiveAncestor of a cut vertex of `slot`, which fan_ holds. When the packets agree with the mesh the
// answer is a neighbour of v_s (it becomes an apex of f_l or f_r), and an active vertex whose id is a
// prefix of the cut's is its only active ancestor; so one id per neighbour replaces the walk down from
// the root (one dependent load per level). The walk remains for the rest: the forced chain (v_l == v_r
// need not be adjacent to v_s) and the error.
uint32_t SelectiveMesh::cut_ancestor(VertexId cut, uint32_t slot) const {
  if (!is_vertex(cut)) return kNone;
  for (uint32_t h : fan_) {
    const uint32_t w = head(h);
    if (is_ancestor_or_self(hierarchy_->id(w), cut)) return w;
  }
  const uint32_t a = active_ancestor(cut);
  if (a == kNone)
    fail(kWhere, "vertex " + to_string(hierarchy_->id(slot)) + ": no active ancestor for cut vertex " + to_string(cut));
  return a;
}

// The fan split of docs/internals.md: v_s's faces from (v_s, v_l, ·) CCW to (v_s, ·, v_r) go to v_t,
// the rest to v_u; f_l = (t, u, l) and f_r = (u, t, r) fill the gap. On an open fan a side may lie on
// the boundary: with no face (v_s, v_l, ·) (edge t-l was a border) v_t's faces start at the beginning of
// the fan, with no face (v_s, ·, v_r) they run to its end, and with neither (or a one-sided split whose
// only side is a border) v_t keeps only the new faces. Everything is checked before the first write,
// so inconsistent packets leave the mesh as it was.
void SelectiveMesh::split_fan(uint32_t s, uint32_t l, uint32_t r, bool closed) {  // fan_: s's fan
  const uint32_t t = hierarchy_->first_child(s), u = t + 1;
  const uint32_t n = uint32_t(fan_.size());
  // Half-edges between s and the cut vertices, kNone on a border: s->l (becomes t->l), l->s (l->u),
  // r->s (r->t), s->r (u->r). ia / ib: fan positions of the faces holding s->l / r->s.
  uint32_t ia = kNone, ib = kNone, la = kNone, rb = kNone;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t h = fan_[i], p = prev_edge(h);
    if (head(h) == l) ia = i;
    if (head(h) == r) rb = h;
    if (corner_[p] == l) la = p;
    if (corner_[p] == r) ib = i;
  }
  const auto reject = [&](const std::string& why) { fail(kWhere, "vsplit " + to_string(hierarchy_->id(s)) + ": " + why); };
  for (auto [v, found] : {std::pair{l, ia != kNone || la != kNone}, std::pair{r, ib != kNone || rb != kNone}})
    if (v != kNone && !found) reject("cut vertex " + to_string(hierarchy_->id(v)) + " is not a neighbour");
  if ((l == kNone || r == kNone || (ia == kNone && ib == kNone)) && closed) reject("boundary split of an interior vertex");

  const uint32_t ha = ia != kNone ? fan_[ia] : kNone;
  const uint32_t gb = ib != kNone ? prev_edge(fan_[ib]) : kNone;
  for (uint32_t h : fan_) corner_[h] = u;
  if (ia != kNone || ib != kNone) {
    const uint32_t first = ia != kNone ? ia : 0, last = ib != kNone ? ib : n - 1;
    for (uint32_t i = first;; i = i + 1 == n ? 0 : i + 1) {
      corner_[fan_[i]] = t;
      if (i == last) break;
    }
  }
  const uint32_t fl = l != kNone ? new_face(t, u, l) : kNone;
  const uint32_t fr = r != kNone ? new_face(u, t, r) : kNone;
  if (fl != kNone) {  // half-edges t->u, u->l, l->t
    link(3 * fl + 1, la);
    link(3 * fl + 2, ha);
  }
  if (fr != kNone) {  // half-edges u->t, t->r, r->u
    link(3 * fr + 1, gb);
    link(3 * fr + 2, rb);
  }
  if (fl != kNone && fr != kNone) link(3 * fl, 3 * fr);
  deactivate(s);
  activate(t, fl != kNone ? 3 * fl : 3 * fr + 1);
  activate(u, fl != kNone ? 3 * fl + 1 : 3 * fr);
}

VSplitResult SelectiveMesh::vsplit(uint32_t slot) {
  sync_slots();
  if (!is_active(slot))
    fail(kWhere, "vsplit of inactive vertex " + (slot < hierarchy_->size() ? to_string(hierarchy_->id(slot)) : "?"));
  // SelStreamVSplit (kim-lee-kobbelt §5.3) without recursion: v_l == v_r must be split first, and that
  // split may in turn wait for another. Every stacked vertex is active and distinct unless the packets
  // are cyclic, which the size bound catches.
  stack_.clear();
  stack_.push_back(slot);
  while (!stack_.empty()) {
    const uint32_t s = stack_.back();
    if (!is_active(s)) fail(kWhere, "cyclic split order at " + to_string(hierarchy_->id(s)));
    if (hierarchy_->is_leaf(s)) return {false, s};
    const bool closed = gather_fan(s, fan_);
    const uint32_t l = cut_ancestor(hierarchy_->cut_left(s), s);
    const uint32_t r = cut_ancestor(hierarchy_->cut_right(s), s);
    if (l != kNone && l == r) {
      if (stack_.size() > active_.size()) fail(kWhere, "cyclic split order at " + to_string(hierarchy_->id(s)));
      stack_.push_back(l);
      continue;
    }
    split_fan(s, l, r, closed);
    stack_.pop_back();
  }
  return {true, kNone};
}

// Link condition: the common neighbours of t and u are exactly the apexes of the faces on edge t-u;
// any other common neighbour would end up on a doubled edge and pinch the surface.
bool SelectiveMesh::link_condition(uint32_t t, uint32_t l, uint32_t r) {
  if (++stamp_ == 0) {  // wrapped: clear so stale marks cannot match
    std::fill(mark_.begin(), mark_.end(), 0);
    stamp_ = 1;
  }
  for (uint32_t h : fan_) mark_[head(h)] = mark_[corner_[prev_edge(h)]] = stamp_;
  for (uint32_t h : fan_u_) {
    for (uint32_t w : {head(h), corner_[prev_edge(h)]})
      if (w != t && w != l && w != r && mark_[w] == stamp_) return false;
  }
  return true;
}

// The partial order of §5.3 read backwards. A performed split q whose cut vertices have the active
// ancestors t and u would see v_l == v_r once they merge: a front no sequence of vsplits can reach, in
// which q's own collapse is stuck for good. So q's subtree must collapse first. In the dual view q's
// f_l and f_r appear as faces (A, B, ·) and (B', A', ·) with A, A' below q's v_t and B, B' below its
// v_u; the one whose apex is t lies in t's fan (fan_), so checking that fan finds every such q.
bool SelectiveMesh::breaks_split_order(uint32_t t, uint32_t u) const {
  const VertexHierarchy& h = *hierarchy_;
  const VertexId id_t = h.id(t), id_u = h.id(u);
  for (uint32_t e : fan_) {
    const VertexId a = h.id(head(e)), b = h.id(corner_[prev_edge(e)]);
    if (a.tree != b.tree) continue;
    // Lowest common ancestor of two distinct front vertices: the longest common prefix of their ids.
    const int da = a.depth(), db = b.depth(), d = std::min(da, db);
    const uint64_t pa = a.node >> (da - d), pb = b.node >> (db - d);
    if (pa == pb) continue;  // one above the other: not a front, cannot happen
    const int below = std::bit_width(pa ^ pb);  // levels from the common ancestor q down to depth d
    // q is (da - d) + below parents up from A: a short climb beats a hash probe (two cache misses),
    // a long one (dozens of levels) does not.
    uint32_t q = head(e);
    if (da - d + below <= kMaxClimb) {
      for (int k = da - d + below; k > 0; --k) q = h.parent(q);
    } else {
      q = h.find({a.tree, pa >> below});
      if (q == kNone) continue;  // cannot happen: q is an ancestor of a front vertex
    }
    // A below q's v_t: the face is (A, B, t) = f_l(q), else (B, A, t) = f_r(q).
    const bool a_first = ((pa >> (below - 1)) & 1) == 0;
    const VertexId cut_t = a_first ? h.cut_left(q) : h.cut_right(q);
    const VertexId cut_u = a_first ? h.cut_right(q) : h.cut_left(q);
    if (is_vertex(cut_t) && is_vertex(cut_u) && is_ancestor_or_self(id_t, cut_t) && is_ancestor_or_self(id_u, cut_u))
      return true;
  }
  return false;
}

bool SelectiveMesh::ecol(uint32_t p) {
  sync_slots();
  if (p >= hierarchy_->size() || hierarchy_->is_leaf(p)) fail(kWhere, "ecol of a node with no known children");
  const uint32_t t = hierarchy_->first_child(p), u = t + 1;
  if (!is_active(t) || !is_active(u)) return false;
  const bool t_closed = gather_fan(t, fan_);
  uint32_t el = kNone, er = kNone;  // t->u in f_l = (t, u, l); t->r in f_r = (u, t, r)
  for (uint32_t h : fan_) {
    if (head(h) == u) el = h;
    if (corner_[prev_edge(h)] == u) er = h;
  }
  // The faces on t-u must be those vsplit(p) would create here: same sides, apexes ActiveAncestor(v̂)
  // (an active vertex is the active ancestor of v̂ exactly when its id is a prefix of v̂'s).
  const VertexId cut_l = hierarchy_->cut_left(p), cut_r = hierarchy_->cut_right(p);
  if ((el != kNone) != is_vertex(cut_l) || (er != kNone) != is_vertex(cut_r)) return false;
  const uint32_t l = el != kNone ? corner_[prev_edge(el)] : kNone, r = er != kNone ? head(er) : kNone;
  if (l != kNone && !is_ancestor_or_self(hierarchy_->id(l), cut_l)) return false;
  if (r != kNone && !is_ancestor_or_self(hierarchy_->id(r), cut_r)) return false;
  if (l == r) return false;  // both kNone cannot pass the checks above, so l == r means one apex twice
  if (breaks_split_order(t, u)) return false;
  // Seen with a virtual vertex joined to every border vertex, an interior edge between two border
  // vertices fails the link condition too: merging them would pinch the surface at one vertex.
  const bool u_closed = gather_fan(u, fan_u_);
  if (el != kNone && er != kNone && !t_closed && !u_closed) return false;
  if (!link_condition(t, l, r)) return false;
  // No vertex may be left without faces: an apex whose only face is the one removed, or p itself.
  const uint32_t removed = (el != kNone) + (er != kNone);
  if (fan_.size() + fan_u_.size() == 2 * removed) return false;
  if (el != kNone && twin_[next_edge(el)] == kNone && twin_[prev_edge(el)] == kNone) return false;
  if (er != kNone && twin_[er] == kNone && twin_[next_edge(er)] == kNone) return false;

  // Glue the two edges of each removed face that become one, and keep the apexes' half-edges alive.
  if (el != kNone) {
    const uint32_t a = twin_[next_edge(el)], b = twin_[prev_edge(el)];  // l->u and t->l
    link(a, b);
    if (out_[l] / 3 == el / 3) out_[l] = a != kNone ? a : next_edge(b);
  }
  if (er != kNone) {
    const uint32_t c = twin_[er], d = twin_[next_edge(er)];  // r->t and u->r
    link(c, d);
    if (out_[r] / 3 == er / 3) out_[r] = c != kNone ? c : next_edge(d);
  }
  const uint32_t fl = el != kNone ? el / 3 : kNone, fr = er != kNone ? er / 3 : kNone;
  uint32_t out = kNone;
  for (const std::vector<uint32_t>* fan : {&fan_, &fan_u_}) {
    for (uint32_t h : *fan) {
      if (h / 3 == fl || h / 3 == fr) continue;
      corner_[h] = p;
      out = h;
    }
  }
  if (fl != kNone) free_face(fl);
  if (fr != kNone) free_face(fr);
  deactivate(t);
  deactivate(u);
  activate(p, out);
  return true;
}

}  // namespace pms
