// Compressed multilevel levels (multilevel/codec.h; docs/multilevel-format.md, "Compressed levels").
// A level states its representatives first, so that each of its vertices is predicted from the vertex it
// stands at in coarser LODs (the paper's forest: the vertex it collapsed onto, a neighbour), or, with none
// known yet, from the vertex before it. Corners go against a move-to-front list of the last corners
// (a collapse's triangles share its edge), a miss as its difference to the last miss. Every integer is
// sent as its bit length under one of the level's prefix codes, then the bits below its leading one (the
// scheme of DEFLATE's distance codes, RFC 1951 §3.2.5, with one class per length). Both sides run the
// same emitter: the encoder twice (counting, then writing), the decoder as its mirror.
#include "multilevel/codec.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>

#include "common/bit_cast.h"
#include "common/bit_stream.h"
#include "common/error.h"
#include "common/prefix_code.h"
#include "multilevel/binary_internal.h"

namespace pms {
namespace {

using multilevel_binary::CompressedHead;
using multilevel_binary::LevelHeader;
using multilevel_binary::TexcoordBox;

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;
constexpr uint32_t kClasses = 33;  // bit lengths 0..32
constexpr uint32_t kRecent = 16;   // corners the move-to-front list holds
constexpr uint32_t kCornerSymbols = kRecent + kClasses;

// One prefix code per kind of integer; kAxis + k for coordinate k, kTexcoord + k for texture coordinate k
// (after the corner's, so that a mesh without texture coordinates codes as it did before them).
// The secondary array's vertex gaps come last, for the same reason; its positions use the axes' codes.
enum Slot : uint32_t { kRepGap, kRepDelta, kAxis, kCorner = kAxis + 3, kTexcoord, kChangedGap = kTexcoord + 2, kSlots };
constexpr uint32_t alphabet(uint32_t slot) { return slot == kCorner ? kCornerSymbols : kClasses; }
constexpr const char* kSlotNames[kSlots] = {
    "representative vertex", "representative", "x", "y", "z", "corner", "u", "v", "changed vertex"};

// Grid coordinates per vertex in the encoder's and decoder's arrays: the position's, then the texture
// coordinates' (when the mesh has them).
uint32_t grid_width(uint32_t dimension, bool texcoords) { return dimension + (texcoords ? 2 : 0); }

uint32_t zigzag(int64_t x) { return uint32_t(x >= 0 ? uint64_t(x) << 1 : (uint64_t(-x) << 1) - 1); }
int64_t unzigzag(uint32_t z) { return z & 1 ? -int64_t(z >> 1) - 1 : int64_t(z >> 1); }

std::string str(uint64_t v) { return std::to_string(v); }

// The move-to-front list of a level's last corners.
class RecentCorners {
 public:
  // Position of `v`, or kRecent if it is not held.
  uint32_t find(uint32_t v) const {
    for (uint32_t i = 0; i < size_; ++i)
      if (list_[i] == v) return i;
    return kRecent;
  }
  uint32_t at(uint32_t i) const { return list_[i]; }
  uint32_t size() const { return size_; }
  void touch(uint32_t v, uint32_t i) {  // i: find(v)
    if (i == kRecent) i = size_ < kRecent ? size_++ : kRecent - 1;
    std::move_backward(list_.begin(), list_.begin() + i, list_.begin() + i + 1);
    list_[0] = v;
  }

 private:
  std::array<uint32_t, kRecent> list_{};
  uint32_t size_ = 0;
};

// What the encoder knows of one level and what its decoder will know.
struct LevelInput {
  const MultilevelMesh& mesh;
  std::span<const uint32_t> quantized;  // grid_width per vertex
  std::span<const uint8_t> known;       // per vertex: its representative is stated by this level or a coarser one
  uint32_t level, position_bits, texcoord_bits;
  std::vector<uint32_t> pairs;  // (vertex, representative), by vertex
  const PositionGrid& grid;
  const ChangedVertices* changed;  // its LOD's secondary array, when the mesh has them
};

// The vertex whose grid coordinates predict v's; kNoRep: the middle of the grid.
uint32_t predictor(uint32_t v, uint32_t representative) {
  return representative != kNoRep ? representative : v > 0 ? v - 1 : kNoRep;
}

// The encoder's pass over a level: counts symbols (Counter) or writes them (Writer).
template <class Sink>
void emit_level(const LevelInput& in, Sink& sink) {
  const MultilevelMesh& m = in.mesh;
  const uint32_t d = m.dimension, level = in.level;
  const uint32_t v_end = m.vertex_count[level], v_begin = v_end - m.level_vertices(level);
  const uint32_t t_end = m.triangle_count[level], t_begin = t_end - m.level_triangles(level);
  int64_t previous = -1;
  for (size_t k = 0; k < in.pairs.size(); k += 2) {
    const uint32_t v = in.pairs[k], r = in.pairs[k + 1];
    sink.value(kRepGap, uint32_t(v - previous - 1));
    sink.value(kRepDelta, v - r - 1);
    previous = v;
  }
  sink.end_part(&CompressedLevelBits::representatives);
  const int64_t middle = int64_t(1) << (in.position_bits - 1);
  const bool texcoords = !m.texcoords.empty();
  const int64_t texcoord_middle = texcoords ? int64_t(1) << (in.texcoord_bits - 1) : 0;
  const uint32_t w = grid_width(d, texcoords);
  for (uint32_t v = v_begin; v < v_end; ++v) {
    const uint32_t from = predictor(v, in.known[v] ? m.representative[v] : kNoRep);
    const auto axis = [&](uint32_t slot, uint32_t k, int64_t fallback) {
      const int64_t guess = from == kNoRep ? fallback : in.quantized[size_t(from) * w + k];
      sink.value(slot, zigzag(int64_t(in.quantized[size_t(v) * w + k]) - guess));
    };
    for (uint32_t k = 0; k < d; ++k) axis(kAxis + k, k, middle);
    if (!m.normals.empty())
      for (int k = 0; k < 3; ++k) sink.raw(bit_cast<uint32_t>(m.normals[size_t(v) * 3 + k]), 32);
    if (!m.colors.empty())
      for (int k = 0; k < 4; ++k) sink.raw(m.colors[size_t(v) * 4 + k], 8);
    if (texcoords)
      for (uint32_t k = 0; k < 2; ++k) axis(kTexcoord + k, d + k, texcoord_middle);
  }
  sink.end_part(&CompressedLevelBits::vertices);
  RecentCorners recent;
  int64_t last_miss = 0;
  for (size_t c = size_t(t_begin) * 3; c < size_t(t_end) * 3; ++c) {
    const uint32_t v = m.triangles[c], i = recent.find(v);
    if (i < kRecent) {
      sink.symbol(kCorner, i);
    } else {
      const uint32_t z = zigzag(int64_t(v) - last_miss);
      sink.symbol(kCorner, kRecent + uint32_t(std::bit_width(z)));
      sink.below_leading_one(z);
      last_miss = v;
    }
    recent.touch(v, i);
  }
  sink.end_part(&CompressedLevelBits::triangles);
  if (!in.changed) return;
  // Each changed vertex after the last, its position on the grid against its own, its values raw.
  const ChangedVertices& c = *in.changed;
  int64_t last = -1;
  for (size_t i = 0; i < c.size(); ++i) {
    const uint32_t v = c.vertex[i];
    sink.value(kChangedGap, uint32_t(v - last - 1));
    last = v;
    float p[3] = {0, 0, 0};
    uint32_t q[3];
    std::copy_n(&c.positions[i * d], d, p);
    quantize_position(in.grid, p, q);
    for (uint32_t k = 0; k < d; ++k) sink.value(kAxis + k, zigzag(int64_t(q[k]) - in.quantized[size_t(v) * w + k]));
    for (size_t k = 0; k < (c.normals.empty() ? 0 : 3); ++k) sink.raw(bit_cast<uint32_t>(c.normals[i * 3 + k]), 32);
    for (size_t k = 0; k < (c.colors.empty() ? 0 : 4); ++k) sink.raw(c.colors[i * 4 + k], 8);
  }
  sink.end_part(&CompressedLevelBits::changed);
}

struct Counter {
  std::array<std::vector<uint64_t>, kSlots> counts;
  Counter() {
    for (uint32_t s = 0; s < kSlots; ++s) counts[s].assign(alphabet(s), 0);
  }
  void symbol(uint32_t slot, uint32_t s) { ++counts[slot][s]; }
  void value(uint32_t slot, uint32_t x) { symbol(slot, uint32_t(std::bit_width(x))); }
  void below_leading_one(uint32_t) {}
  void raw(uint32_t, unsigned) {}
  void end_part(uint64_t CompressedLevelBits::*) {}
};

struct Writer {
  BitWriter& w;
  const std::array<PrefixCode, kSlots>& codes;
  CompressedLevelBits& bits;
  uint64_t part_start = w.size();
  void symbol(uint32_t slot, uint32_t s) { codes[slot].write(w, s); }
  void value(uint32_t slot, uint32_t x) {
    symbol(slot, uint32_t(std::bit_width(x)));
    below_leading_one(x);
  }
  void below_leading_one(uint32_t x) {
    const unsigned n = unsigned(std::bit_width(x));
    if (n > 1) w.bits(x, n - 1);
  }
  void raw(uint32_t x, unsigned n) { w.bits(x, n); }
  void end_part(uint64_t CompressedLevelBits::*part) {
    bits.*part = w.size() - part_start;
    part_start = w.size();
  }
};

// Which codes a level with these counts carries (a code for nothing is left out).
std::array<bool, kSlots> slots_used(uint32_t dimension, bool texcoords, uint32_t vertices, uint32_t triangles,
                                    uint32_t representatives, uint32_t changed) {
  std::array<bool, kSlots> used{};
  used[kRepGap] = used[kRepDelta] = representatives > 0;
  for (uint32_t k = 0; k < dimension; ++k) used[kAxis + k] = vertices > 0 || changed > 0;
  used[kCorner] = triangles > 0;
  used[kTexcoord] = used[kTexcoord + 1] = texcoords && vertices > 0;
  used[kChangedGap] = changed > 0;
  return used;
}

std::vector<uint8_t> encode_level(const LevelInput& in, CompressedLevelBits& bits) {
  const MultilevelMesh& m = in.mesh;
  const LevelHeader h{in.level, m.level_vertices(in.level), m.level_triangles(in.level), uint32_t(in.pairs.size() / 2)};
  const uint32_t changed = in.changed ? uint32_t(in.changed->size()) : 0;
  Counter counter;
  emit_level(in, counter);
  const auto used = slots_used(m.dimension, !m.texcoords.empty(), h.vertices, h.triangles, h.representatives, changed);
  std::array<PrefixCode, kSlots> codes;
  BitWriter w;
  for (uint32_t field : {h.level, h.vertices, h.triangles, h.representatives}) w.bits(field, 32);
  if (in.changed) w.bits(changed, 32);
  for (uint32_t s = 0; s < kSlots; ++s)
    if (used[s]) {
      codes[s] = PrefixCode::from_counts(counter.counts[s]);
      codes[s].serialize(w);
    }
  bits = {};
  bits.header = w.size();
  Writer writer{w, codes, bits};
  emit_level(in, writer);
  bits.header += 8 * w.bytes().size() - w.size();  // the last byte's padding
  return w.bytes();
}

uint32_t read_value(BitReader& r, const PrefixCode& code, const char* field) {
  const uint32_t n = code.read(r, field);
  if (n <= 1) return n;
  return uint32_t(1) << (n - 1) | uint32_t(r.bits(n - 1, field));
}

// decode_compressed_level, with the level's reader open.
class LevelDecoder {
 public:
  LevelDecoder(const std::string& where, std::span<const uint8_t> bytes, const CompressedLevelContext& c)
      : where_(where), r_(bytes, where), c_(c) {}

  std::vector<uint8_t> run(std::vector<uint32_t>& quantized) {
    read_header();
    read_representatives();
    read_vertices(quantized);
    read_triangles();
    if (c_.changed) read_changed(quantized);
    return multilevel_binary::level_section_bytes(h_, positions_, normals_, colors_, texcoords_, triangles_, pairs_,
                                                  c_.changed ? &changed_ : nullptr);
  }

 private:
  [[noreturn]] void error(const std::string& what) const {
    fail(where_, "compressed level " + str(c_.level) + ": " + what);
  }

  void read_header() {
    h_.level = uint32_t(r_.bits(32, "level"));
    h_.vertices = uint32_t(r_.bits(32, "vertex count"));
    h_.triangles = uint32_t(r_.bits(32, "triangle count"));
    h_.representatives = uint32_t(r_.bits(32, "representative count"));
    if (h_.level != c_.level) error("says it is level " + str(h_.level));
    if (h_.vertices > c_.vertices_left || h_.triangles > c_.triangles_left ||
        h_.representatives > c_.representatives_left)
      error("more vertices, triangles or representatives than the head's totals leave");
    if (c_.changed) {
      changed_count_ = uint32_t(r_.bits(32, "secondary array count"));
      if (changed_count_ > c_.changed_left) error("more secondary array entries than the head's total leaves");
    }
    const auto used =
        slots_used(c_.dimension, c_.texcoords, h_.vertices, h_.triangles, h_.representatives, changed_count_);
    for (uint32_t s = 0; s < kSlots; ++s)
      if (used[s]) codes_[s] = PrefixCode::deserialize(r_, alphabet(s), kSlotNames[s]);
  }

  void read_representatives() {
    const uint64_t n = c_.representative->size();
    pairs_.reserve(2 * size_t(h_.representatives));
    int64_t previous = -1;
    for (uint32_t i = 0; i < h_.representatives; ++i) {
      const uint64_t v = uint64_t(previous + 1) + read_value(r_, codes_[kRepGap], kSlotNames[kRepGap]);
      if (v >= n) error("a representative of vertex " + str(v) + ", beyond the mesh's " + str(n));
      const uint32_t delta = read_value(r_, codes_[kRepDelta], kSlotNames[kRepDelta]);
      if (delta >= v) error("vertex " + str(v) + " has a representative below 0");
      pairs_.insert(pairs_.end(), {uint32_t(v), uint32_t(v - 1 - delta)});
      previous = int64_t(v);
    }
  }

  // A vertex's representative as the encoder saw it: from a coarser level, else from this one's pairs
  // (sorted by vertex, so one cursor walks them along the vertices).
  uint32_t representative_of(uint32_t v, size_t& cursor) const {
    const uint32_t r = (*c_.representative)[v];
    if (r != kNoRep) return r;
    while (cursor < pairs_.size() && pairs_[cursor] < v) cursor += 2;
    return cursor < pairs_.size() && pairs_[cursor] == v ? pairs_[cursor + 1] : kNoRep;
  }

  void read_vertices(std::vector<uint32_t>& quantized) {
    const uint32_t d = c_.dimension, v_begin = c_.vertices_loaded, w = grid_width(d, c_.texcoords);
    positions_.reserve(size_t(h_.vertices) * d);
    quantized.reserve(quantized.size() + size_t(h_.vertices) * w);
    size_t cursor = 0;
    for (uint32_t v = v_begin; v < v_begin + h_.vertices; ++v) {
      const uint32_t from = predictor(v, representative_of(v, cursor));
      // Grid coordinate k of v (k < w), under `slot`, on a grid of `bits`.
      const auto axis = [&](uint32_t slot, uint32_t k, uint32_t bits) {
        const int64_t guess = from == kNoRep ? int64_t(1) << (bits - 1) : quantized[size_t(from) * w + k];
        const int64_t x = guess + unzigzag(read_value(r_, codes_[slot], kSlotNames[slot]));
        if (x < 0 || x > (int64_t(1) << bits) - 1) error("vertex " + str(v) + " is off the " + str(bits) + "-bit grid");
        quantized.push_back(uint32_t(x));
        return uint32_t(x);
      };
      uint32_t q[3] = {0, 0, 0};
      for (uint32_t k = 0; k < d; ++k) q[k] = axis(kAxis + k, k, c_.grid.bits);
      float p[3];
      dequantize_position(c_.grid, q, p);
      positions_.insert(positions_.end(), p, p + d);
      if (c_.normals)
        for (int k = 0; k < 3; ++k) normals_.push_back(bit_cast<float>(uint32_t(r_.bits(32, "normal"))));
      if (c_.colors)
        for (int k = 0; k < 4; ++k) colors_.push_back(uint8_t(r_.bits(8, "colour")));
      if (c_.texcoords) {
        uint32_t t[3] = {0, 0, 0};
        for (uint32_t k = 0; k < 2; ++k) t[k] = axis(kTexcoord + k, d + k, c_.texcoord_grid.bits);
        dequantize_position(c_.texcoord_grid, t, p);
        texcoords_.insert(texcoords_.end(), p, p + 2);
      }
    }
  }

  void read_triangles() {
    const uint64_t n = c_.representative->size();
    triangles_.reserve(3 * size_t(h_.triangles));
    RecentCorners recent;
    int64_t last_miss = 0;
    for (uint64_t c = 0; c < 3 * uint64_t(h_.triangles); ++c) {
      const uint32_t s = codes_[kCorner].read(r_, kSlotNames[kCorner]);
      uint32_t v = 0, i = kRecent;
      if (s < kRecent) {
        if (s >= recent.size())
          error("corner " + str(c) + " names recent corner " + str(s) + " of " + str(recent.size()));
        i = s;
        v = recent.at(i);
      } else {
        const uint32_t bits = s - kRecent;
        const uint32_t z = bits <= 1 ? bits : uint32_t(1) << (bits - 1) | uint32_t(r_.bits(bits - 1, "corner"));
        const int64_t x = last_miss + unzigzag(z);
        if (x < 0 || uint64_t(x) >= n) error("corner " + str(c) + " names vertex " + str(x) + " of " + str(n));
        v = uint32_t(x);
        last_miss = x;
      }
      recent.touch(v, i);
      triangles_.push_back(v);
    }
  }

  // The secondary array: vertices of the LOD (below what is loaded with this level), ascending by
  // construction; positions on the grid. The loader checks the rest (take_changed).
  void read_changed(const std::vector<uint32_t>& quantized) {
    const uint32_t d = c_.dimension, w = grid_width(d, c_.texcoords);
    const uint64_t n_l = uint64_t(c_.vertices_loaded) + h_.vertices;
    int64_t last = -1;
    for (uint32_t i = 0; i < changed_count_; ++i) {
      const uint64_t v = uint64_t(last + 1) + read_value(r_, codes_[kChangedGap], kSlotNames[kChangedGap]);
      if (v >= n_l) error("the secondary array changes vertex " + str(v) + ", which is not in LOD " + str(c_.level));
      last = int64_t(v);
      changed_.vertex.push_back(uint32_t(v));
      uint32_t q[3] = {0, 0, 0};
      for (uint32_t k = 0; k < d; ++k) {
        const int64_t x = int64_t(quantized[v * w + k]) + unzigzag(read_value(r_, codes_[kAxis + k], kSlotNames[kAxis + k]));
        if (x < 0 || x > (int64_t(1) << c_.grid.bits) - 1)
          error("the secondary array puts vertex " + str(v) + " off the " + str(c_.grid.bits) + "-bit grid");
        q[k] = uint32_t(x);
      }
      float p[3];
      dequantize_position(c_.grid, q, p);
      changed_.positions.insert(changed_.positions.end(), p, p + d);
      if (c_.normals)
        for (int k = 0; k < 3; ++k) changed_.normals.push_back(bit_cast<float>(uint32_t(r_.bits(32, "normal"))));
      if (c_.colors)
        for (int k = 0; k < 4; ++k) changed_.colors.push_back(uint8_t(r_.bits(8, "colour")));
    }
  }

  const std::string& where_;
  BitReader r_;
  const CompressedLevelContext& c_;
  LevelHeader h_{};
  uint32_t changed_count_ = 0;
  ChangedVertices changed_;
  std::array<PrefixCode, kSlots> codes_;
  std::vector<uint32_t> pairs_, triangles_;
  std::vector<float> positions_, normals_, texcoords_;
  std::vector<uint8_t> colors_;
};

}  // namespace

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
  std::vector<uint8_t> stated(m.vertices(), 0), known(m.vertices(), 0);
  if (bits) bits->clear();
  for (uint32_t level = m.level_count(); level-- > 0;) {
    LevelInput in{m,
                  quantized,
                  known,
                  level,
                  position_bits,
                  texcoord_bits,
                  level_representatives(m, level, stated),
                  grid,
                  m.changed.empty() ? nullptr : &m.changed[level]};
    std::vector<uint32_t> order(in.pairs.size() / 2);
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return in.pairs[2 * a] < in.pairs[2 * b]; });
    std::vector<uint32_t> sorted;
    sorted.reserve(in.pairs.size());
    for (uint32_t i : order) sorted.insert(sorted.end(), {in.pairs[2 * i], in.pairs[2 * i + 1]});
    in.pairs = std::move(sorted);
    for (size_t k = 0; k < in.pairs.size(); k += 2) known[in.pairs[k]] = 1;
    CompressedLevelBits level_bits;
    parts.levels.push_back(encode_level(in, level_bits));
    if (bits) bits->push_back(level_bits);
  }
  return parts;
}

std::vector<uint8_t> decode_compressed_level(const std::string& where, std::span<const uint8_t> level,
                                             const CompressedLevelContext& context, std::vector<uint32_t>& quantized) {
  return LevelDecoder(where, level, context).run(quantized);
}

}  // namespace pms
