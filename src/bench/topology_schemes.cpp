// kim-lee-kobbelt 2005 §7.2, Table 2, measured. The schemes, as the paper describes them:
// - To et al. 1999 over Xia & Varshney 1996's explicit 1-ring: v_s, v_t and N(v_s), v_l and v_r first (v_u
//   is v_t + 1, Hoppe's array rule). A list of varying length needs its length: an Elias-γ valence here.
// - El-Sana et al. over El-Sana & Varshney 1999's implicit 1-ring: v_s, v_t, v_l, v_r and the min/max ids
//   of N(v_s).
// - Southern et al. 2001 over Hoppe 1997's 4-face vsplit: v_s, v_t, f_l, f_r, f_n0..f_n3; the paper's
//   variation drops f_l, f_r (f_l = 2 v_s + #F(M^0), f_r = f_l + 1).
// - kim-lee-kobbelt (Kim & Lee 2001's truly selective vsplit): v_s, v̂_l, v̂_r, children implied by the
//   <tree-id, node-id> heap rule.
#include "bench/topology_schemes.h"

#include <algorithm>
#include <bit>

#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/packet_bits.h"
#include "spm/split_record.h"

namespace pms::bench {
namespace {

// The mesh M^i of the PM sequence: corner triples and each vertex's faces (unordered), by node index.
class PmMesh {
 public:
  explicit PmMesh(const ModelData& model)
      : model_(model), active_(model.node_count(), 0), faces_of_(model.node_count()) {
    for (uint32_t r = 0; r < model.root_count; ++r) active_[r] = 1;
    for (size_t i = 0; i + 2 < model.base_faces.size(); i += 3)
      add_face(model.base_faces[i], model.base_faces[i + 1], model.base_faces[i + 2]);
  }

  SplitTopology split(uint32_t s) {
    SplitTopology out;
    out.vs = s;
    out.vt = model_.first_child[s];
    const uint32_t t = out.vt, u = t + 1;
    out.vl = active_ancestor(model_.cut_left[s]);
    out.vr = active_ancestor(model_.cut_right[s]);
    neighbours(s, out);
    const std::vector<uint32_t> t_faces = fan_between(s, out.vl, out.vr);
    for (uint32_t f : faces_of_[s]) {
      const bool to_t = std::find(t_faces.begin(), t_faces.end(), f) != t_faces.end();
      std::replace(&corner_[3 * size_t(f)], &corner_[3 * size_t(f) + 3], s, to_t ? t : u);
      faces_of_[to_t ? t : u].push_back(f);
    }
    faces_of_[s] = {};
    active_[s] = 0;
    active_[t] = active_[u] = 1;
    if (out.vl != kNone) {
      out.fl = add_face(t, u, out.vl);
      out.fn[0] = face_beside(out.fl, u, out.vl);
      out.fn[1] = face_beside(out.fl, out.vl, t);
    }
    if (out.vr != kNone) {
      out.fr = add_face(u, t, out.vr);
      out.fn[2] = face_beside(out.fr, t, out.vr);
      out.fn[3] = face_beside(out.fr, out.vr, u);
    }
    return out;
  }

  // The faces as leaf triples once every split is made.
  std::vector<uint32_t> faces() const { return corner_; }
  uint32_t face_count() const { return uint32_t(corner_.size() / 3); }

 private:
  uint32_t add_face(uint32_t a, uint32_t b, uint32_t c) {
    const uint32_t f = face_count();
    for (uint32_t v : {a, b, c}) {
      corner_.push_back(v);
      faces_of_[v].push_back(f);
    }
    return f;
  }

  uint32_t active_ancestor(uint32_t leaf) const {
    if (leaf == kNone) return kNone;
    uint32_t n = leaf;
    while (!active_[n]) {
      n = model_.parent[n];
      if (n == kNone) fail("Table 2", "a cut vertex has no active ancestor");
    }
    return n;
  }

  // v's corner in f: the face reads (v, next, prev) CCW.
  uint32_t next_of(uint32_t f, uint32_t v) const {
    const uint32_t* c = &corner_[3 * size_t(f)];
    return c[0] == v ? c[1] : c[1] == v ? c[2] : c[0];
  }
  uint32_t prev_of(uint32_t f, uint32_t v) const {
    const uint32_t* c = &corner_[3 * size_t(f)];
    return c[0] == v ? c[2] : c[1] == v ? c[0] : c[1];
  }

  // N(v_s), v_l and v_r first; a cut vertex that is not a neighbour means the model and the replay disagree.
  void neighbours(uint32_t s, SplitTopology& out) const {
    std::vector<uint32_t>& n = out.neighbours;
    for (uint32_t f : faces_of_[s])
      for (uint32_t w : {next_of(f, s), prev_of(f, s)})
        if (std::find(n.begin(), n.end(), w) == n.end()) n.push_back(w);
    size_t front = 0;
    for (uint32_t cut : {out.vl, out.vr}) {
      if (cut == kNone) continue;
      const auto it = std::find(n.begin() + ptrdiff_t(front), n.end(), cut);
      if (it == n.end()) fail("Table 2", "split " + std::to_string(s) + ": a cut vertex is not beside v_s");
      std::iter_swap(n.begin() + ptrdiff_t(front++), it);
    }
    const auto [lo, hi] = std::minmax_element(n.begin(), n.end());
    if (lo != n.end()) out.min_id = *lo, out.max_id = *hi;
  }

  // The face of s whose next corner is `a`, kNone if none.
  uint32_t face_after(uint32_t s, uint32_t a) const {
    for (uint32_t f : faces_of_[s])
      if (next_of(f, s) == a) return f;
    return kNone;
  }

  // The face of s whose prev corner is `b`, kNone if none.
  uint32_t face_before(uint32_t s, uint32_t b) const {
    for (uint32_t f : faces_of_[s])
      if (prev_of(f, s) == b) return f;
    return kNone;
  }

  // The faces v_t gets: CCW from (s, l, ·) to (s, ·, r); where either face is missing (a boundary side, or a
  // cut vertex at the open fan's far end) from the open fan's start or to its end, none when both are
  // (docs/internals.md; SelectiveMesh::split_fan). Bounded by the fan's size whatever the data.
  std::vector<uint32_t> fan_between(uint32_t s, uint32_t l, uint32_t r) const {
    const uint32_t first = l != kNone ? face_after(s, l) : kNone, last = r != kNone ? face_before(s, r) : kNone;
    std::vector<uint32_t> fan;
    if (first == kNone && last == kNone) return fan;
    uint32_t f = first;
    if (f == kNone)
      for (uint32_t g : faces_of_[s])  // the open fan's start: no face of s ends where g begins
        if (face_before(s, next_of(g, s)) == kNone) f = g;
    while (f != kNone && fan.size() < faces_of_[s].size()) {
      fan.push_back(f);
      if (f == last) break;
      f = face_after(s, prev_of(f, s));
    }
    return fan;
  }

  // The face other than f that has the directed edge b -> a (f has a -> b), kNone on a boundary.
  uint32_t face_beside(uint32_t f, uint32_t a, uint32_t b) const {
    for (uint32_t g : faces_of_[a])
      if (g != f && prev_of(g, a) == b) return g;
    return kNone;
  }

  const ModelData& model_;
  std::vector<uint8_t> active_;
  std::vector<uint32_t> corner_;
  std::vector<std::vector<uint32_t>> faces_of_;
};

// Writes a scheme's fields for one split, each at its width; none = the top value of the width.
class Fields {
 public:
  Fields(unsigned vertex_bits, unsigned face_bits, uint32_t vertices, uint32_t faces)
      : vertex_bits_(vertex_bits), face_bits_(face_bits), vertices_(vertices), faces_(faces) {}
  void vertex(uint32_t v) { put(v == kNone ? vertices_ : v, vertex_bits_); }
  void face(uint32_t f) { put(f == kNone ? faces_ : f, face_bits_); }
  void gamma(uint32_t n) {  // Elias γ of n + 1
    const unsigned width = unsigned(std::bit_width(uint64_t(n) + 1));
    w_.bits(0, width - 1);
    w_.bits(uint64_t(n) + 1, width);
  }
  uint64_t bits() const { return w_.size(); }
  uint32_t indices() const { return indices_; }

 private:
  void put(uint64_t value, unsigned width) {
    w_.bits(value, width);
    ++indices_;
  }
  unsigned vertex_bits_, face_bits_;
  uint32_t vertices_, faces_;
  BitWriter w_;
  uint32_t indices_ = 0;
};

struct Scheme {
  const char *framework, *scheme, *fields;
  uint32_t paper_bits;
  void (*write)(const SplitTopology&, Fields&);
};

void write_explicit_ring(const SplitTopology& s, Fields& w) {
  w.vertex(s.vs);
  w.vertex(s.vt);
  w.gamma(uint32_t(s.neighbours.size()));
  size_t i = 0;
  for (uint32_t cut : {s.vl, s.vr}) w.vertex(cut == kNone ? kNone : s.neighbours[i++]);
  for (; i < s.neighbours.size(); ++i) w.vertex(s.neighbours[i]);
}

void write_implicit_ring(const SplitTopology& s, Fields& w) {
  for (uint32_t v : {s.vs, s.vt, s.vl, s.vr, s.min_id, s.max_id}) w.vertex(v);
}

void write_four_face(const SplitTopology& s, Fields& w) {
  w.vertex(s.vs);
  w.vertex(s.vt);
  w.face(s.fl);
  w.face(s.fr);
  for (uint32_t f : s.fn) w.face(f);
}

void write_implicit_four_face(const SplitTopology& s, Fields& w) {
  w.vertex(s.vs);
  w.vertex(s.vt);
  for (uint32_t f : s.fn) w.face(f);
}

constexpr Scheme kSchemes[] = {
    {"To et al. [29]", "explicit 1-ring (Xia & Varshney 1996)", "v_s, v_t, |N|, N(v_s)", 256, write_explicit_ring},
    {"El-Sana et al. [7,8]", "implicit 1-ring (El-Sana & Varshney 1999)", "v_s, v_t, v_l, v_r, min/max of N(v_s)", 192,
     write_implicit_ring},
    {"Southern et al. [28]", "4-face (Hoppe 1997)", "v_s, v_t, f_l, f_r, f_n0..3", 256, write_four_face},
    {"variation of [28]", "implicit 4-face", "v_s, v_t, f_n0..3", 192, write_implicit_four_face},
};
constexpr size_t kSchemeCount = std::size(kSchemes);

}  // namespace

std::vector<uint32_t> replay_pm_topology(const ModelData& model,
                                         const std::function<void(const SplitTopology&)>& visit) {
  check_node_arrays(model);
  PmMesh mesh(model);
  for (uint32_t node : model.split_order) visit(mesh.split(node));
  return mesh.faces();
}

std::vector<SchemeBits> table2_bits(const ModelData& model, const protocol::StreamContext& context) {
  const uint32_t vertices = uint32_t(model.node_count());
  const uint32_t faces = uint32_t(model.base_faces.size() / 3 + 2 * model.split_order.size());  // at most
  const unsigned vertex_bits = unsigned(std::bit_width(vertices)), face_bits = unsigned(std::bit_width(faces));
  std::vector<SchemeBits> rows(kSchemeCount + 2);
  uint64_t splits = 0, ours_coded = 0;
  replay_pm_topology(model, [&](const SplitTopology& s) {
    for (size_t k = 0; k < kSchemeCount; ++k) {
      Fields fitted(vertex_bits, face_bits, vertices, faces);
      kSchemes[k].write(s, fitted);
      rows[k].indices += fitted.indices();
      rows[k].bits_fitted += double(fitted.bits());
      rows[k].bits_32 += 32.0 * fitted.indices();  // the paper's convention counts indices only
    }
    ours_coded += protocol::packet_bits(split_record(model, s.vs), context).topology;
    ++splits;
  });
  for (size_t k = 0; k < kSchemeCount; ++k) {
    rows[k].framework = kSchemes[k].framework;
    rows[k].scheme = kSchemes[k].scheme;
    rows[k].fields = kSchemes[k].fields;
    rows[k].paper_bits = kSchemes[k].paper_bits;
  }
  const double ids = 3.0 * double(splits);
  rows[kSchemeCount] = {"kim-lee-kobbelt", "truly selective (Kim & Lee 2001)", "v_s, v̂_l, v̂_r", 96, ids,
                        32 * ids, double(vertex_bits) * ids};
  rows[kSchemeCount + 1] = {"pmstream packet", "the same, <tree-id, node-id> code", "v_s, v̂_l, v̂_r, cut flags", 96,
                            ids, 32 * ids, double(ours_coded)};
  for (SchemeBits& row : rows) {
    const double n = double(std::max<uint64_t>(splits, 1));
    row.indices /= n;
    row.bits_32 /= n;
    row.bits_fitted /= n;
  }
  return rows;
}

}  // namespace pms::bench
