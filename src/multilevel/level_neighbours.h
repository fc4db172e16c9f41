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

// A set of vertices emptied in O(1): a round number per vertex, the set being those of the current round.
// What lets a coder test "is it already listed / next to that vertex" in constant time.
class VertexMarks {
 public:
  void reset(uint32_t vertices) {
    round_.assign(vertices, 0);
    current_ = 0;
  }
  void clear() {
    if (++current_ == 0) {  // the rounds wrapped: start them again
      std::fill(round_.begin(), round_.end(), 0);
      current_ = 1;
    }
  }
  void add(uint32_t v) { round_[v] = current_; }
  bool has(uint32_t v) const { return round_[v] == current_; }

 private:
  std::vector<uint32_t> round_;
  uint32_t current_ = 0;
};

class LevelNeighbours {
 public:
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
  // Edges kept per vertex: a vertex's first neighbours are the ones coding uses, and the cap bounds the
  // work a hostile mesh (one vertex in every triangle) can ask for.
  static constexpr uint32_t kMaxNeighbours = 24;

  // For a mesh of `vertices` (what a head announces: 4 bytes a vertex until triangles name them).
  void reset(uint32_t vertices);
  bool empty() const { return slot_.empty(); }
  uint32_t vertices() const { return uint32_t(slot_.size()); }
  bool named(uint32_t v) const { return slot_[v] != kNone; }
  // v's neighbours in the order their edges arrived (empty when no triangle names v).
  std::span<const uint32_t> of(uint32_t v) const {
    return slot_[v] == kNone ? std::span<const uint32_t>{} : std::span<const uint32_t>(lists_[slot_[v]]);
  }
  void add_triangle(const uint32_t corner[3]);

 private:
  void add_edge(uint32_t a, uint32_t b);
  std::vector<uint32_t> slot_;  // per vertex, its list in lists_, or kNone
  std::vector<std::vector<uint32_t>> lists_;
};

// The vertices a corner is likely to be, best first: the ones the caller names, the next vertex of the level no triangle has named
// yet, the vertices next to both corners before it, next to the one just before, next to the first, and
// the level's last corners (a move-to-front list). At most kCandidates, each once, none a corner already
// decided; a corner outside them is an escape.
class CornerCandidates {
 public:
  static constexpr uint32_t kCandidates = 31;  // symbol kCandidates is the escape
  static constexpr uint32_t kRecent = 8;

  // `decided`: the triangle's corners before this one (0 to 2); `first`: vertices to lead the list (the
  // ones the level's structure points at); `cursor`: kNone when the level has no vertex left unnamed.
  // `listed` and `beside` (sized to the mesh) are scratch.
  std::span<const uint32_t> build(const LevelNeighbours& mesh, std::span<const uint32_t> decided,
                                  std::span<const uint32_t> first, uint32_t cursor, VertexMarks& listed,
                                  VertexMarks& beside);
  // After each triangle: its corners go to the front of the recent list.
  void remember(const uint32_t corner[3]);

 private:
  void add(uint32_t v, VertexMarks& listed);
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
  VertexMarks listed, beside;            // scratch sets of the coder's lists
};

}  // namespace pms
