// Compressed multilevel levels (multilevel/codec.h; docs/multilevel-format.md, "Compressed levels").
// A level is coded against everything coded before it. Its triangles come as a mesh coder's would
// (Edgebreaker's traversal makes a new triangle's corners the vertices next to the gate's; here the
// triangles keep the structure's order, so each corner is coded as its place in a list of the vertices the
// mesh so far puts next to the corners before it, led by the level's next unnamed vertex: a corner
// outside the list is an escape, its difference to the last escape). Then its vertices, each predicted
// from what is decoded around it (the triangles of this level and the coarser ones name them: see
// Prediction), so what is coded is the vertex's offset from its surroundings, not its edge. Every decision and integer
// goes through one adaptive range coder (common/range_coder.h) with models fresh per level, so a level
// decodes with nothing but the levels before it. Encoder and decoder run the same function, `code_level`.
#include "multilevel/codec.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>

#include "common/bit_cast.h"
#include "common/error.h"
#include "common/range_coder.h"
#include "multilevel/binary_internal.h"
#include "multilevel/level_neighbours.h"

namespace pms {
namespace {

using multilevel_binary::CompressedHead;
using multilevel_binary::LevelHeader;
using multilevel_binary::TexcoordBox;

constexpr uint32_t kNone = LevelNeighbours::kNone;
constexpr uint32_t kEscape = CornerCandidates::kCandidates;

// Grid coordinates per vertex in the encoder's and decoder's arrays: the position's, then the texture
// coordinates' (when the mesh has them).
uint32_t grid_width(uint32_t dimension, bool texcoords) { return dimension + (texcoords ? 2 : 0); }

uint32_t zigzag(int64_t x) { return uint32_t(x >= 0 ? uint64_t(x) << 1 : (uint64_t(-x) << 1) - 1); }
int64_t unzigzag(uint32_t z) { return z & 1 ? -int64_t(z >> 1) - 1 : int64_t(z >> 1); }

std::string str(uint64_t v) { return std::to_string(v); }

// What a level holds and both sides know before its body: its counts and the mesh's layout.
struct LevelShape {
  uint32_t level, v_begin, vertices, triangles, representatives, changed;
  uint32_t dimension;
  bool normals, colors, texcoords;
  uint32_t position_bits, texcoord_bits;
  uint64_t mesh_vertices;  // every level's
};

// A level's values: the encoder's input, the decoder's output. Grid coordinates live in
// CompressedLevelState::quantized (the encoder's holds every vertex's from the start).
struct LevelValues {
  std::vector<uint32_t> pairs;      // (vertex, representative), by vertex
  std::vector<uint32_t> triangles;  // 3 per triangle
  std::vector<uint32_t> normals;    // 3 per vertex, the floats' bits
  std::vector<uint8_t> colors;      // 4 per vertex
  std::vector<uint32_t> changed_vertex, changed_grid, changed_normals;  // dimension grid coordinates per entry
  std::vector<uint8_t> changed_colors;
};

// The level's adaptive models, fresh for each level.
struct Models {
  AdaptiveInteger rep_gap, rep_delta, escape, changed_gap, anchor_step;
  AdaptiveBit anchored;
  std::array<AdaptiveSymbol<5>, 3> corner;  // per corner of a triangle: its candidate, or the escape
  std::array<AdaptiveInteger, 5> axis;      // positions' x y z, then texture coordinates' u v
  std::array<AdaptiveInteger, 3> changed_axis;
};

class EncodeSide {
 public:
  static constexpr bool kEncoding = true;
  explicit EncodeSide(CompressedLevelBits& bits) : bits_(bits) {}
  uint32_t integer(AdaptiveInteger& model, uint32_t x) {
    rc_.integer(model, x);
    return x;
  }
  uint32_t symbol(AdaptiveSymbol<5>& model, uint32_t s) {
    rc_.symbol(model, s);
    return s;
  }
  bool bit(AdaptiveBit& model, bool b) {
    rc_.bit(model, b);
    return b;
  }
  uint32_t raw(uint32_t x, unsigned n) {
    rc_.raw(x, n);
    return x;
  }
  void end_part(uint64_t CompressedLevelBits::*part) {
    const double now = rc_.bits();
    bits_.*part = uint64_t(now - part_start_ + 0.5);
    part_start_ = now;
  }
  [[noreturn]] void error(const std::string& what) const { fail("multilevel", "compressed level: " + what); }
  std::vector<uint8_t> finish() { return rc_.finish(); }

 private:
  RangeEncoder rc_;
  CompressedLevelBits& bits_;
  double part_start_ = 0;
};

class DecodeSide {
 public:
  static constexpr bool kEncoding = false;
  DecodeSide(std::span<const uint8_t> body, const std::string& where) : rc_(body, where), where_(where) {}
  uint32_t integer(AdaptiveInteger& model, uint32_t) { return rc_.integer(model); }
  uint32_t symbol(AdaptiveSymbol<5>& model, uint32_t) { return rc_.symbol(model); }
  bool bit(AdaptiveBit& model, bool) { return rc_.bit(model) != 0; }
  uint32_t raw(uint32_t, unsigned n) { return rc_.raw(n); }
  void end_part(uint64_t CompressedLevelBits::*) {}
  [[noreturn]] void error(const std::string& what) const { fail(where_, what); }
  void expect_end() const { rc_.expect_end(); }

 private:
  RangeDecoder rc_;
  const std::string& where_;
};

// A grid coordinate `guess + offset` of `what` vertex v, checked on a grid of `bits` (the error's text is
// made only for an error: this runs for every coordinate).
template <class Side>
uint32_t on_grid(const Side& side, int64_t guess, uint32_t zigzagged, uint32_t bits, const char* what, uint64_t v) {
  const int64_t x = guess + unzigzag(zigzagged);
  if (x < 0 || x > (int64_t(1) << bits) - 1)
    side.error(what + str(v) + " is off the " + str(bits) + "-bit grid");
  return uint32_t(x);
}

// Each pair as its vertex's gap to the last pair's, then its distance below the vertex.
template <class Side>
void code_representatives(Side& side, const LevelShape& s, LevelValues& x, Models& m, std::vector<uint32_t>& known) {
  int64_t previous = -1;
  for (uint32_t i = 0; i < s.representatives; ++i) {
    const uint64_t v =
        uint64_t(previous + 1) + side.integer(m.rep_gap, Side::kEncoding ? uint32_t(x.pairs[2 * i] - previous - 1) : 0);
    if (v >= s.mesh_vertices) side.error("a representative of vertex " + str(v) + ", beyond the mesh's " + str(s.mesh_vertices));
    const uint32_t delta =
        side.integer(m.rep_delta, Side::kEncoding ? uint32_t(x.pairs[2 * i] - x.pairs[2 * i + 1] - 1) : 0);
    if (delta >= v) side.error("vertex " + str(v) + " has a representative below 0");
    if (!Side::kEncoding) x.pairs.insert(x.pairs.end(), {uint32_t(v), uint32_t(v - 1 - delta)});
    known[v] = uint32_t(v - 1 - delta);
    previous = int64_t(v);
  }
  side.end_part(&CompressedLevelBits::representatives);
}

// Steps a chain of representatives may take before a corner counts as reaching nothing: chains are short
// in builds, and the bound keeps a hostile one from costing its length per corner.
constexpr uint32_t kMaxChain = 64;

// Where vertex x stands in LOD l (the vertices below n_l) by the representatives known so far; kNone if
// its chain stops or runs too long.
uint32_t standing(const std::vector<uint32_t>& representative, uint32_t x, uint32_t n_l) {
  for (uint32_t step = 0; x != kNone && x >= n_l; ++step) x = step < kMaxChain ? representative[x] : kNone;
  return x;
}

// The vertices a level's pairs state (finer than its LOD), by the vertex of the level's LOD they stand at:
// a corner that reaches an anchor is that vertex or one of these.
class Descendants {
 public:
  Descendants(const LevelShape& s, const std::vector<uint32_t>& pairs, const std::vector<uint32_t>& representative) {
    const uint32_t n_l = s.v_begin + s.vertices;
    for (size_t i = 0; i < pairs.size(); i += 2)
      if (pairs[i] >= n_l)
        if (const uint32_t at = standing(representative, pairs[i], n_l); at != kNone) by_.push_back({at, pairs[i]});
    std::sort(by_.begin(), by_.end());
  }
  // `a` and what stands at it, at most `cap`, into buffer `which` (0 or 1): a triangle's first corner
  // asks for its anchor, the others for the anchor's representative, each the same for a run of triangles,
  // so each buffer keeps its last answer.
  std::span<const uint32_t> of(uint32_t a, size_t cap, int which) {
    Answer& answer = answers_[which];
    if (answer.vertex == a && !answer.list.empty()) return answer.list;
    answer.vertex = a;
    answer.list.assign(1, a);
    for (auto it = std::lower_bound(by_.begin(), by_.end(), std::pair<uint32_t, uint32_t>{a, 0});
         it != by_.end() && it->first == a && answer.list.size() < cap; ++it)
      answer.list.push_back(it->second);
    return answer.list;
  }

 private:
  struct Answer {
    uint32_t vertex = kNone;
    std::vector<uint32_t> list;
  };
  std::vector<std::pair<uint32_t, uint32_t>> by_;
  std::array<Answer, 2> answers_;
};

// A triangle's first corner: whether it stands at a vertex of the level (its anchor: builds put the
// triangles by anchor), the anchor as a step from the last one, then the corner among the anchor and what
// stands at it. Its other corners lead with the anchor's representative and what stands at that.
template <class Side>
void code_triangles(Side& side, const LevelShape& s, LevelValues& x, Models& m, CompressedLevelState& state) {
  LevelNeighbours& mesh = state.neighbours;
  CornerCandidates candidates;
  Descendants descendants(s, x.pairs, state.representative);
  const uint32_t v_end = s.v_begin + s.vertices;
  uint32_t cursor = s.v_begin;
  int64_t last_escape = 0, last_anchor = s.v_begin;
  for (uint32_t t = 0; t < s.triangles; ++t) {
    while (cursor < v_end && mesh.named(cursor)) ++cursor;
    uint32_t c[3];
    uint32_t anchor = Side::kEncoding ? standing(state.representative, x.triangles[3 * size_t(t)], v_end) : kNone;
    if (Side::kEncoding && anchor != kNone && anchor < s.v_begin) anchor = kNone;
    if (side.bit(m.anchored, anchor != kNone)) {
      const int64_t a = last_anchor + unzigzag(side.integer(m.anchor_step, zigzag(int64_t(anchor) - last_anchor)));
      if (a < s.v_begin || a >= v_end) side.error("triangle " + str(t) + " stands at vertex " + str(a) + ", not of the level");
      anchor = uint32_t(a);
      last_anchor = a;
    }
    for (uint32_t k = 0; k < 3; ++k) {
      std::span<const uint32_t> lead;
      if (anchor != kNone) {
        const uint32_t at = k == 0 ? anchor : state.representative[anchor];
        if (at != kNone) lead = descendants.of(at, CornerCandidates::kCandidates, k == 0 ? 0 : 1);
      }
      const uint32_t unnamed = cursor < v_end ? cursor : kNone;
      const auto candidates_until = [&](CornerCandidates::Until until) {
        return candidates.build(mesh, {c, k}, lead, unnamed, until);
      };
      const uint32_t actual = Side::kEncoding ? x.triangles[3 * size_t(t) + k] : 0;
      uint32_t symbol = kEscape;
      if (Side::kEncoding) {
        const std::span<const uint32_t> list = candidates_until({actual, kEscape});
        if (!list.empty() && list.back() == actual) symbol = uint32_t(list.size() - 1);
      }
      symbol = side.symbol(m.corner[k], symbol);
      if (symbol == kEscape) {
        const int64_t v = last_escape + unzigzag(side.integer(m.escape, zigzag(int64_t(actual) - last_escape)));
        if (v < 0 || uint64_t(v) >= s.mesh_vertices)
          side.error("triangle " + str(t) + " names vertex " + str(v) + " of " + str(s.mesh_vertices));
        c[k] = uint32_t(v);
        last_escape = v;
        continue;
      }
      const std::span<const uint32_t> list = Side::kEncoding ? candidates.list() : candidates_until({kNone, symbol});
      if (symbol >= list.size())
        side.error("triangle " + str(t) + " names candidate " + str(symbol) + " of " + str(list.size()));
      c[k] = list[symbol];
      mesh.prefetch(c[k]);  // its list is read for the next corner and when the triangle is added
    }
    mesh.add_triangle(c);
    candidates.remember(c);
    if (!Side::kEncoding) x.triangles.insert(x.triangles.end(), c, c + 3);
  }
  side.end_part(&CompressedLevelBits::triangles);
}

// Ring members a vertex's prediction looks at: enough for a vertex's triangles, few enough that a
// hostile mesh's crowded vertices cost little.
constexpr uint32_t kPredictionRing = 8;

// What predicts vertex v from the vertices decoded before it (index below v): the parallelograms of its
// known triangles (v, a, b) across from a decoded triangle (b, a, c), a + b - c (touma and gotsman 1998),
// averaged; without one, its representative's position when one is stated (the vertex it splits from sits
// where it ends up, near); else the mean of its decoded neighbours; without those, the vertex before it.
struct Prediction {
  std::array<std::array<uint32_t, 3>, kPredictionRing * kPredictionRing> terms;  // (a, b, c): a + b - c
  uint32_t parallelograms = 0;
  std::array<uint32_t, kPredictionRing> ring;
  uint32_t around = 0;
  uint32_t representative = kNone;

  void find(const LevelNeighbours& mesh, uint32_t v, uint32_t v_representative) {
    representative = v_representative < v ? v_representative : kNone;
    parallelograms = around = 0;
    for (uint32_t u : mesh.of(v))
      if (u < v && around < kPredictionRing) ring[around++] = u;
    for (uint32_t i = 0; i < around; ++i) {
      const uint32_t a = ring[i];
      for (uint32_t j = i + 1; j < around; ++j) {
        const uint32_t b = ring[j];
        if (!mesh.adjacent(a, b)) continue;
        for (uint32_t c : mesh.of(b))
          if (c != v && c < v && mesh.adjacent(a, c)) {
            terms[parallelograms++] = {a, b, c};
            break;
          }
      }
    }
  }
  // Grid coordinate k (of w per vertex in q); `fallback` when nothing is decoded around v.
  int64_t at(const std::vector<uint32_t>& q, uint32_t w, uint32_t k, int64_t fallback) const {
    const auto value = [&](uint32_t u) { return int64_t(q[size_t(u) * w + k]); };
    int64_t sum = 0;
    if (parallelograms > 0) {
      for (uint32_t i = 0; i < parallelograms; ++i) sum += value(terms[i][0]) + value(terms[i][1]) - value(terms[i][2]);
      return rounded_mean(sum, parallelograms);
    }
    if (representative != kNone) return value(representative);
    if (around == 0) return fallback;
    for (uint32_t i = 0; i < around; ++i) sum += value(ring[i]);
    return rounded_mean(sum, around);
  }
  static int64_t rounded_mean(int64_t sum, uint32_t n) {
    return sum >= 0 ? (sum + n / 2) / n : -((-sum + n / 2) / n);
  }
};

// Vertices ahead whose neighbours' lists are fetched while one is decoded: its prediction reads the lists
// of vertices anywhere in the mesh, and fetching them early hides the wait.
constexpr uint32_t kPrefetchAhead = 2;

template <class Side>
void code_vertices(Side& side, const LevelShape& s, LevelValues& x, Models& m, CompressedLevelState& state) {
  const uint32_t d = s.dimension, w = grid_width(d, s.texcoords);
  std::vector<uint32_t>& q = state.quantized;
  Prediction prediction;
  const uint32_t v_end = s.v_begin + s.vertices;
  for (uint32_t v = s.v_begin; v < v_end; ++v) {
    if (v + kPrefetchAhead < v_end) state.neighbours.prefetch_around(v + kPrefetchAhead);
    prediction.find(state.neighbours, v, state.representative[v]);
    // Grid coordinate k of v, on a grid of `bits`.
    const auto axis = [&](uint32_t k, uint32_t bits) {
      const int64_t guess = prediction.at(q, w, k, v > 0 ? int64_t(q[size_t(v - 1) * w + k]) : int64_t(1) << (bits - 1));
      const uint32_t z = side.integer(m.axis[k], Side::kEncoding ? zigzag(int64_t(q[size_t(v) * w + k]) - guess) : 0);
      const uint32_t value = on_grid(side, guess, z, bits, "vertex ", v);
      if (!Side::kEncoding) q.push_back(value);
    };
    for (uint32_t k = 0; k < d; ++k) axis(k, s.position_bits);
    if (s.normals)
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t n = side.raw(Side::kEncoding ? x.normals[size_t(v - s.v_begin) * 3 + k] : 0, 32);
        if (!Side::kEncoding) x.normals.push_back(n);
      }
    if (s.colors)
      for (uint32_t k = 0; k < 4; ++k) {
        const uint32_t c = side.raw(Side::kEncoding ? x.colors[size_t(v - s.v_begin) * 4 + k] : 0, 8);
        if (!Side::kEncoding) x.colors.push_back(uint8_t(c));
      }
    if (s.texcoords)
      for (uint32_t k = d; k < d + 2; ++k) axis(k, s.texcoord_bits);
  }
  side.end_part(&CompressedLevelBits::vertices);
}

// The secondary array: vertices of the LOD, ascending, each on the grid against its own coordinates, its
// normal and colour raw. The loader checks the rest (take_changed).
template <class Side>
void code_changed(Side& side, const LevelShape& s, LevelValues& x, Models& m, const std::vector<uint32_t>& q) {
  const uint32_t d = s.dimension, w = grid_width(d, s.texcoords);
  const uint64_t n_l = uint64_t(s.v_begin) + s.vertices;
  int64_t last = -1;
  for (uint32_t i = 0; i < s.changed; ++i) {
    const uint64_t v = uint64_t(last + 1) +
                       side.integer(m.changed_gap, Side::kEncoding ? uint32_t(x.changed_vertex[i] - last - 1) : 0);
    if (v >= n_l) side.error("the secondary array changes vertex " + str(v) + ", which is not in LOD " + str(s.level));
    last = int64_t(v);
    if (!Side::kEncoding) x.changed_vertex.push_back(uint32_t(v));
    for (uint32_t k = 0; k < d; ++k) {
      const int64_t own = q[size_t(v) * w + k];
      const uint32_t z =
          side.integer(m.changed_axis[k], Side::kEncoding ? zigzag(int64_t(x.changed_grid[size_t(i) * d + k]) - own) : 0);
      const uint32_t value = on_grid(side, own, z, s.position_bits, "the secondary array's vertex ", v);
      if (!Side::kEncoding) x.changed_grid.push_back(value);
    }
    for (uint32_t k = 0; k < (s.normals ? 3u : 0u); ++k) {
      const uint32_t n = side.raw(Side::kEncoding ? x.changed_normals[size_t(i) * 3 + k] : 0, 32);
      if (!Side::kEncoding) x.changed_normals.push_back(n);
    }
    for (uint32_t k = 0; k < (s.colors ? 4u : 0u); ++k) {
      const uint32_t c = side.raw(Side::kEncoding ? x.changed_colors[size_t(i) * 4 + k] : 0, 8);
      if (!Side::kEncoding) x.changed_colors.push_back(uint8_t(c));
    }
  }
  side.end_part(&CompressedLevelBits::changed);
}

// A level's body, in the order the format gives: representatives, triangles, vertices, secondary array.
template <class Side>
void code_level(Side& side, const LevelShape& s, LevelValues& x, CompressedLevelState& state) {
  if (state.neighbours.vertices() != s.mesh_vertices) {
    state.neighbours.reset(uint32_t(s.mesh_vertices));
    state.representative.assign(s.mesh_vertices, kNone);
  }
  Models m;
  code_representatives(side, s, x, m, state.representative);
  code_triangles(side, s, x, m, state);
  code_vertices(side, s, x, m, state);
  if (s.changed > 0) code_changed(side, s, x, m, state.quantized);
}

// The level's counts as its first 16 bytes (20 with secondary arrays): level, vertices, triangles,
// representatives[, secondary array entries], u32 little-endian.
constexpr size_t kCountBytes = sizeof(LevelHeader);

std::vector<uint8_t> encode_level(const MultilevelMesh& m, uint32_t level, std::vector<uint32_t> pairs,
                                  CompressedLevelState& state, uint32_t position_bits, uint32_t texcoord_bits,
                                  const PositionGrid& grid, CompressedLevelBits& bits) {
  const ChangedVertices* changed = m.changed.empty() ? nullptr : &m.changed[level];
  const uint32_t v_end = m.vertex_count[level], v_begin = v_end - m.level_vertices(level);
  const uint32_t t_end = m.triangle_count[level], t_begin = t_end - m.level_triangles(level);
  const LevelShape s{level,
                     v_begin,
                     v_end - v_begin,
                     t_end - t_begin,
                     uint32_t(pairs.size() / 2),
                     changed ? uint32_t(changed->size()) : 0,
                     m.dimension,
                     !m.normals.empty(),
                     !m.colors.empty(),
                     !m.texcoords.empty(),
                     position_bits,
                     texcoord_bits,
                     m.vertices()};
  LevelValues x;
  x.pairs = std::move(pairs);
  x.triangles.assign(m.triangles.begin() + 3 * size_t(t_begin), m.triangles.begin() + 3 * size_t(t_end));
  for (size_t i = size_t(v_begin) * 3; i < (s.normals ? size_t(v_end) * 3 : 0); ++i)
    x.normals.push_back(bit_cast<uint32_t>(m.normals[i]));
  if (s.colors) x.colors.assign(m.colors.begin() + 4 * size_t(v_begin), m.colors.begin() + 4 * size_t(v_end));
  if (changed) {
    x.changed_vertex = changed->vertex;
    for (size_t i = 0; i < changed->size(); ++i) {
      float p[3] = {0, 0, 0};
      uint32_t q[3];
      std::copy_n(&changed->positions[i * m.dimension], m.dimension, p);
      quantize_position(grid, p, q);
      x.changed_grid.insert(x.changed_grid.end(), q, q + m.dimension);
    }
    for (float n : changed->normals) x.changed_normals.push_back(bit_cast<uint32_t>(n));
    x.changed_colors = changed->colors;
  }
  std::vector<uint8_t> out(kCountBytes);
  const LevelHeader h{level, s.vertices, s.triangles, s.representatives};
  std::memcpy(out.data(), &h, sizeof h);
  if (changed) {
    out.resize(kCountBytes + 4);
    std::memcpy(out.data() + kCountBytes, &s.changed, 4);
  }
  bits = {};
  EncodeSide side(bits);
  code_level(side, s, x, state);
  const std::vector<uint8_t> body = side.finish();
  out.insert(out.end(), body.begin(), body.end());
  bits.header = 8 * out.size() - bits.total();  // the counts and the coder's flush
  return out;
}

}  // namespace

std::vector<uint8_t> decode_compressed_level(const std::string& where, std::span<const uint8_t> level,
                                             const CompressedLevelContext& c, CompressedLevelState& state) {
  const std::string at = where + ": compressed level " + str(c.level);
  const size_t count_bytes = kCountBytes + (c.changed ? 4 : 0);
  if (level.size() < count_bytes) fail(at, "truncated");
  LevelHeader h;
  std::memcpy(&h, level.data(), sizeof h);
  uint32_t changed = 0;
  if (c.changed) std::memcpy(&changed, level.data() + kCountBytes, 4);
  if (h.level != c.level) fail(at, "says it is level " + str(h.level));
  if (h.vertices > c.vertices_left || h.triangles > c.triangles_left || h.representatives > c.representatives_left)
    fail(at, "more vertices, triangles or representatives than the head's totals leave");
  if (changed > c.changed_left) fail(at, "more secondary array entries than the head's total leaves");
  const LevelShape s{c.level,      c.vertices_loaded, h.vertices, h.triangles, h.representatives, changed,
                     c.dimension,  c.normals,         c.colors,   c.texcoords, c.grid.bits,       c.texcoord_grid.bits,
                     c.mesh_vertices};
  const uint32_t d = c.dimension, w = grid_width(d, c.texcoords);
  LevelValues x;
  DecodeSide side(level.subspan(count_bytes), at);
  code_level(side, s, x, state);
  side.expect_end();
  std::vector<float> positions, texcoords;
  positions.reserve(size_t(h.vertices) * d);
  for (uint32_t v = c.vertices_loaded; v < c.vertices_loaded + h.vertices; ++v) {
    uint32_t q[3] = {0, 0, 0};
    float p[3];
    std::copy_n(state.quantized.begin() + long(size_t(v) * w), d, q);
    dequantize_position(c.grid, q, p);
    positions.insert(positions.end(), p, p + d);
    if (!c.texcoords) continue;
    std::copy_n(state.quantized.begin() + long(size_t(v) * w + d), 2, q);
    dequantize_position(c.texcoord_grid, q, p);
    texcoords.insert(texcoords.end(), p, p + 2);
  }
  ChangedVertices changed_vertices;
  changed_vertices.vertex = std::move(x.changed_vertex);
  for (size_t i = 0; i < changed_vertices.vertex.size(); ++i) {
    uint32_t q[3] = {0, 0, 0};
    float p[3];
    std::copy_n(x.changed_grid.begin() + long(i * d), d, q);
    dequantize_position(c.grid, q, p);
    changed_vertices.positions.insert(changed_vertices.positions.end(), p, p + d);
  }
  for (uint32_t n : x.changed_normals) changed_vertices.normals.push_back(bit_cast<float>(n));
  changed_vertices.colors = std::move(x.changed_colors);
  std::vector<float> normals;
  for (uint32_t n : x.normals) normals.push_back(bit_cast<float>(n));
  return multilevel_binary::level_section_bytes(h, positions, normals, x.colors, texcoords, x.triangles, x.pairs,
                                                c.changed ? &changed_vertices : nullptr);
}


namespace {

// A grid of `bits` per axis over the box of `d` values per vertex (the axes past d are flat).
PositionGrid grid_over(const std::vector<float>& values, uint32_t d, uint32_t bits, const char* what) {
  if (bits < 1 || bits > 24) fail("multilevel", std::string(what) + " bits " + str(bits) + " (1 to 24)");
  PositionGrid grid;
  grid.bits = bits;
  for (size_t v = 0; v < values.size() / d; ++v)
    for (uint32_t k = 0; k < d; ++k) {
      const float p = values[v * d + k];
      grid.min[k] = v == 0 ? p : std::min(grid.min[k], p);
      grid.max[k] = v == 0 ? p : std::max(grid.max[k], p);
    }
  return grid;
}

// Every vertex's `d` values on `grid`, into columns [column, column + d) of `q` (`width` per vertex).
void quantize_into(const std::vector<float>& values, uint32_t d, const PositionGrid& grid, std::vector<uint32_t>& q,
                   uint32_t column, uint32_t width) {
  for (size_t v = 0; v < values.size() / d; ++v) {
    float p[3] = {0, 0, 0};
    uint32_t out[3];
    std::copy_n(values.begin() + v * d, d, p);
    quantize_position(grid, p, out);
    std::copy_n(out, d, q.begin() + v * width + column);
  }
}

// `values` (d per vertex) replaced by their grid points.
void snap_all(std::vector<float>& values, uint32_t d, const PositionGrid& grid) {
  for (size_t v = 0; v < values.size() / d; ++v) {
    float p[3] = {0, 0, 0};
    std::copy_n(values.begin() + v * d, d, p);
    snap_position(grid, p, p);
    std::copy_n(p, d, values.begin() + v * d);
  }
}

}  // namespace

PositionGrid multilevel_grid(const MultilevelMesh& m, uint32_t bits) {
  return grid_over(m.positions, m.dimension, bits, "position");
}

PositionGrid multilevel_texcoord_grid(const MultilevelMesh& m, uint32_t bits) {
  return grid_over(m.texcoords, 2, bits, "texture coordinate");
}

MultilevelMesh snapped_multilevel(const MultilevelMesh& mesh, uint32_t bits, uint32_t texcoord_bits) {
  MultilevelMesh out = mesh;
  snap_all(out.positions, mesh.dimension, multilevel_grid(mesh, bits));
  for (ChangedVertices& c : out.changed) snap_all(c.positions, mesh.dimension, multilevel_grid(mesh, bits));
  if (!mesh.texcoords.empty()) snap_all(out.texcoords, 2, multilevel_texcoord_grid(mesh, texcoord_bits));
  return out;
}

MultilevelParts multilevel_compressed_parts(const MultilevelMesh& m, uint32_t position_bits,
                                            std::vector<CompressedLevelBits>* bits, uint32_t texcoord_bits) {
  validate_multilevel("", m);
  const bool texcoords = !m.texcoords.empty();
  const PositionGrid grid = multilevel_grid(m, position_bits);
  const PositionGrid texcoord_grid = texcoords ? multilevel_texcoord_grid(m, texcoord_bits) : PositionGrid{};
  CompressedHead head{multilevel_binary::head_section(m), position_bits, {}, {}, texcoords ? texcoord_bits : 0};
  head.head.reserved = kCompressedLevelsVersion;
  std::copy_n(grid.min, 3, head.min);
  std::copy_n(grid.max, 3, head.max);
  MultilevelParts parts;
  parts.head.resize(sizeof head);
  std::memcpy(parts.head.data(), &head, sizeof head);
  const uint32_t w = grid_width(m.dimension, texcoords);
  std::vector<uint32_t> quantized(size_t(m.vertices()) * w);
  quantize_into(m.positions, m.dimension, grid, quantized, 0, w);
  if (texcoords) {
    TexcoordBox box;
    std::copy_n(texcoord_grid.min, 2, box.min);
    std::copy_n(texcoord_grid.max, 2, box.max);
    parts.head.resize(sizeof head + sizeof box);
    std::memcpy(parts.head.data() + sizeof head, &box, sizeof box);
    quantize_into(m.texcoords, 2, texcoord_grid, quantized, m.dimension, w);
  }
  std::vector<uint8_t> stated(m.vertices(), 0);
  CompressedLevelState state;
  state.quantized = std::move(quantized);
  if (bits) bits->clear();
  for (uint32_t level = m.level_count(); level-- > 0;) {
    // Sorted by vertex: the structure holds one representative per vertex, so the order says nothing.
    const std::vector<uint32_t> pairs = level_representatives(m, level, stated);
    std::vector<uint32_t> order(pairs.size() / 2);
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return pairs[2 * a] < pairs[2 * b]; });
    std::vector<uint32_t> sorted;
    sorted.reserve(pairs.size());
    for (uint32_t i : order) sorted.insert(sorted.end(), {pairs[2 * i], pairs[2 * i + 1]});
    CompressedLevelBits level_bits;
    parts.levels.push_back(
        encode_level(m, level, std::move(sorted), state, position_bits, texcoord_bits, grid, level_bits));
    if (bits) bits->push_back(level_bits);
  }
  return parts;
}

}  // namespace pms
