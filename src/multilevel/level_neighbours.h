// What the compressed levels' coder knows of the mesh between levels (multilevel/codec.h): the edges of
// every triangle coded so far, between the vertices they name (the finest mesh's, as triangles store
// them), and which vertices some triangle names. Encoder and decoder keep the same one, so a corner is
// coded as its place among the vertices the mesh so far puts next to the corners before it.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace pms {

class LevelNeighbours {
 public:
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
  // Edges kept per vertex: a vertex's first neighbours are the ones coding uses, and the cap bounds the
  // work a hostile mesh (one vertex in every triangle) can ask for. With the count, a cache line.
  static constexpr uint32_t kMaxNeighbours = 15;

  // For a mesh of `vertices` (what a head announces: 4 bytes a vertex until triangles name them); the
  // triangles' corners must be below it.
  void reset(uint32_t vertices) {
    vertices_ = vertices;
    block_.clear();
  }
  uint32_t vertices() const { return vertices_; }
  bool named(uint32_t v) const { return v < block_.size() && block_[v].named; }
  // v's neighbours in the order their edges arrived (empty when no triangle names v).
  std::span<const uint32_t> of(uint32_t v) const {
    if (v >= block_.size()) return {};
    const Block& block = block_[v];
    return {block.neighbour.data(), block.count};
  }
  // Whether v's list holds u: a scan of one short list in one place, cheaper than a set indexed by
  // vertex, whose reads land all over memory.
  bool adjacent(uint32_t v, uint32_t u) const {
    const std::span<const uint32_t> list = of(v);
    return std::find(list.begin(), list.end(), u) != list.end();
  }
  // Ask the memory for v's list, or its neighbours' (hints: nothing changes).
  void prefetch(uint32_t v) const {
    if (v < block_.size()) __builtin_prefetch(block_.data() + v);
  }
  void prefetch_around(uint32_t v) const {
    for (uint32_t u : of(v)) __builtin_prefetch(block_.data() + u);
  }
  void add_triangle(const uint32_t corner[3]);

 private:
  void add_edge(uint32_t a, uint32_t b);
  // Every vertex's list in one array indexed by vertex, a cache line each, up to the highest vertex a
  // triangle names: no allocation per vertex, one line per list read, and a level's vertices (numbered
  // together) side by side.
  struct alignas(64) Block {
    uint16_t named = 0, count = 0;
    std::array<uint32_t, kMaxNeighbours> neighbour;
  };
  static_assert(sizeof(Block) == 64);
  uint32_t vertices_ = 0;
  std::vector<Block> block_;
};

// The vertices a corner is likely to be, best first: the ones the caller names, the next vertex of the
// level no triangle has named yet, the vertices next to both corners before it, next to the one just
// before, next to the first, and the level's last corners (a move-to-front list). At most kCandidates,
// each once, none a corner already decided; a corner outside them is an escape.
class CornerCandidates {
 public:
  static constexpr uint32_t kCandidates = 31;  // symbol kCandidates is the escape
  static constexpr uint32_t kRecent = 8;

  // Where the list may stop: once it holds `vertex`, or once it is longer than `place`. A coder needs no
  // more (the encoder looks for its corner, the decoder for the place it decoded), and the rest of the
  // list is where the work is.
  struct Until {
    uint32_t vertex = LevelNeighbours::kNone;
    uint32_t place = kCandidates;
  };

  // `decided`: the triangle's corners before this one (0 to 2); `first`: vertices to lead the list (the
  // ones the level's structure points at); `cursor`: kNone when the level has no vertex left unnamed.
  // The list up to where `until` says.
  std::span<const uint32_t> build(const LevelNeighbours& mesh, std::span<const uint32_t> decided,
                                  std::span<const uint32_t> first, uint32_t cursor, Until until);
  // What the last build listed.
  std::span<const uint32_t> list() const { return {list_.data(), size_}; }
  // After each triangle: its corners go to the front of the recent list.
  void remember(const uint32_t corner[3]);

 private:
  // Lists v unless it is there already or decided; true once the list may stop.
  bool add(uint32_t v, std::span<const uint32_t> decided, const Until& until);
  std::array<uint32_t, kCandidates> list_{};
  uint32_t size_ = 0;
  std::array<uint32_t, kRecent> recent_{};
  uint32_t recent_size_ = 0;
};

// What coding a compressed level (multilevel/codec.h) leaves for the next ones, the same on both sides.
struct CompressedLevelState {
  // Grid coordinates of every loaded vertex: dimension per vertex, then 2 for the texture coordinates if any.
  std::vector<uint32_t> quantized;
  LevelNeighbours neighbours;           // the edges of every loaded triangle
  std::vector<uint32_t> representative;  // every loaded level's, LevelNeighbours::kNone where none is stated
};

}  // namespace pms
