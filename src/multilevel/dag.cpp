// Gueziec, Taubin, Horn, Lazarus 1999, "Local refinement" (Fig. 14): the DAG of collapses, built as the
// paper builds it, by examining the star of each collapsed edge and linking to the collapses that produced
// its vertices; the collapses are the multilevel mesh's own, replayed level by level.
#include "multilevel/dag.h"

#include <algorithm>
#include <cmath>

namespace pms {
namespace {

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;
constexpr uint32_t kNone = MultilevelDag::kNoRemover;

// "Split of `needs` needs split of `needed`" (needed < needs).
struct Requirement {
  uint32_t needs, needed;
};

// The mesh as the replay goes: current corners and, per vertex, the triangles that were live around it.
class CollapseReplay {
 public:
  explicit CollapseReplay(const MultilevelMesh& m)
      : corners_(m.triangles), live_(m.faces(), 1), around_(m.vertices()), producer_(m.vertices(), kNone) {
    for (uint32_t t = 0; t < m.faces(); ++t) {
      if (degenerate(t)) {
        live_[t] = 0;
        continue;
      }
      for (int k = 0; k < 3; ++k) around_[corners_[3 * size_t(t) + k]].push_back(t);
    }
  }

  // Vertices of the live triangles around v, v included, sorted and unique, appended to `out`.
  void append_neighbourhood(uint32_t v, std::vector<uint32_t>& out) {
    std::erase_if(around_[v], [&](uint32_t t) { return !live_[t]; });
    out.push_back(v);
    for (uint32_t t : around_[v])
      for (int k = 0; k < 3; ++k) out.push_back(corners_[3 * size_t(t) + k]);
  }

  uint32_t producer(uint32_t v) const { return producer_[v]; }

  // The normal cone of the live triangles around v and `onto` (MultilevelDag::cone), into cone[0..3].
  void star_normal_cone(const MultilevelMesh& m, uint32_t v, uint32_t onto, float cone[4]) {
    normals_.clear();
    for (uint32_t around : {v, onto}) {
      if (around == kNoRep) continue;
      for (uint32_t t : around_[around])
        if (live_[t]) add_unit_normal(m, t);
    }
    float axis[3] = {0, 0, 0};
    for (size_t i = 0; i < normals_.size(); i += 3)
      for (int k = 0; k < 3; ++k) axis[k] += normals_[i + size_t(k)];
    const float length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    float lowest_cos = length > 0 ? 1.0f : -1.0f;
    for (int k = 0; k < 3; ++k) cone[k] = length > 0 ? axis[k] / length : 0;
    for (size_t i = 0; i < normals_.size(); i += 3)
      lowest_cos = std::min(lowest_cos, cone[0] * normals_[i] + cone[1] * normals_[i + 1] + cone[2] * normals_[i + 2]);
    cone[3] = lowest_cos > 0 ? 1 - lowest_cos * lowest_cos : 2;
  }

  // v onto `onto` (kNoRep: v vanishes): the triangles that degenerate go, with v as their remover when
  // they are of v's level.
  void collapse(uint32_t v, uint32_t onto, uint32_t level, const std::vector<uint32_t>& triangle_level,
                std::vector<uint32_t>& remover) {
    if (onto != kNoRep) producer_[onto] = v;
    for (uint32_t t : around_[v]) {
      if (!live_[t]) continue;
      uint32_t* c = &corners_[3 * size_t(t)];
      for (int k = 0; k < 3; ++k)
        if (c[k] == v) c[k] = onto;
      if (onto == kNoRep || degenerate(t)) {
        live_[t] = 0;
        remover[t] = triangle_level[t] == level ? v : kNone;
      } else {
        around_[onto].push_back(t);
      }
    }
    std::vector<uint32_t>().swap(around_[v]);
  }

  // A level's triangles still there at its end leave without a remover.
  void drop_level(uint32_t begin, uint32_t end) {
    for (uint32_t t = begin; t < end; ++t) live_[t] = 0;
  }

 private:
  void add_unit_normal(const MultilevelMesh& m, uint32_t t) {
    float p[3][3];
    for (int c = 0; c < 3; ++c) m.point(corners_[3 * size_t(t) + size_t(c)], p[c]);
    const float a[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const float b[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const float n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 0)) return;  // a sliver has no direction to add
    for (int k = 0; k < 3; ++k) normals_.push_back(n[k] / length);
  }

  bool degenerate(uint32_t t) const {
    const uint32_t* c = &corners_[3 * size_t(t)];
    return c[0] == c[1] || c[1] == c[2] || c[2] == c[0];
  }

  std::vector<uint32_t> corners_;
  std::vector<uint8_t> live_;
  std::vector<std::vector<uint32_t>> around_;
  std::vector<uint32_t> producer_;  // per vertex: the latest collapse onto it (the paper's "list or hash table")
  std::vector<float> normals_;      // star_normal_cone's scratch
};

// Per element of a prefix-by-level numbering (counts[l]: elements of levels >= l), its level.
std::vector<uint32_t> levels_of(const std::vector<uint32_t>& counts) {
  std::vector<uint32_t> level(counts.empty() ? 0 : counts[0]);
  for (uint32_t l = 0; l < counts.size(); ++l) {
    const uint32_t begin = l + 1 < counts.size() ? counts[l + 1] : 0;
    std::fill(level.begin() + begin, level.begin() + counts[l], l);
  }
  return level;
}

void sort_unique(std::vector<uint32_t>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

float distance(const MultilevelMesh& m, uint32_t a, uint32_t b) {
  float d2 = 0;
  for (uint32_t k = 0; k < m.dimension; ++k) {
    const float d = m.positions[size_t(a) * m.dimension + k] - m.positions[size_t(b) * m.dimension + k];
    d2 += d * d;
  }
  return std::sqrt(d2);
}

// Rows by `row_of`, each sorted and unique.
void to_csr(std::vector<Requirement>& pairs, uint32_t rows, bool by_needs, std::vector<uint32_t>& offsets,
            std::vector<uint32_t>& data) {
  offsets.assign(size_t(rows) + 1, 0);
  for (const Requirement& r : pairs) ++offsets[(by_needs ? r.needs : r.needed) + 1];
  for (uint32_t i = 0; i < rows; ++i) offsets[i + 1] += offsets[i];
  data.resize(pairs.size());
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (const Requirement& r : pairs) data[fill[by_needs ? r.needs : r.needed]++] = by_needs ? r.needed : r.needs;
  // Drop duplicates row by row, compacting in place.
  uint32_t out = 0;
  for (uint32_t i = 0; i < rows; ++i) {
    const auto begin = data.begin() + offsets[i], end = data.begin() + offsets[i + 1];
    std::sort(begin, end);
    const auto last = std::unique(begin, end);
    offsets[i] = out;
    out = uint32_t(std::copy(begin, last, data.begin() + out) - data.begin());
  }
  offsets[rows] = out;
  data.resize(out);
  data.shrink_to_fit();
}

}  // namespace

uint64_t MultilevelDag::memory_bytes() const {
  return sizeof(uint32_t) * (prerequisite_offsets.size() + prerequisites.size() + dependent_offsets.size() +
                             dependents.size() + remover.size()) +
         sizeof(float) * (radius.size() + cone.size());
}

MultilevelDag build_multilevel_dag(const MultilevelMesh& m) {
  MultilevelDag dag;
  dag.vertices = m.vertices();
  dag.top_vertices = m.vertex_count.back();
  dag.remover.assign(m.faces(), kNone);
  dag.radius.assign(dag.vertices - dag.top_vertices, 0.0f);
  dag.cone.assign(4 * size_t(dag.vertices - dag.top_vertices), 0.0f);
  const std::vector<uint32_t> triangle_level = levels_of(m.triangle_count);
  CollapseReplay replay(m);
  std::vector<Requirement> pairs;
  std::vector<uint32_t> neighbours, star, producers;
  for (uint32_t l = 0; l + 1 < m.level_count(); ++l) {
    for (uint32_t v = m.vertex_count[l]; v-- > m.vertex_count[l + 1];) {
      const uint32_t onto = m.representative[v];
      neighbours.clear();
      replay.append_neighbourhood(v, neighbours);
      if (onto != kNoRep) neighbours.push_back(onto);
      sort_unique(neighbours);
      star = neighbours;
      if (onto != kNoRep) replay.append_neighbourhood(onto, star);
      sort_unique(star);
      for (uint32_t y : neighbours) {
        if (y == v) continue;
        dag.radius[v - dag.top_vertices] = std::max(dag.radius[v - dag.top_vertices], distance(m, v, y));
        if (y >= dag.top_vertices) pairs.push_back({v, y});
      }
      producers.clear();
      for (uint32_t y : star)
        if (replay.producer(y) != kNone) producers.push_back(replay.producer(y));
      sort_unique(producers);
      for (uint32_t u : producers) pairs.push_back({u, v});
      replay.star_normal_cone(m, v, onto, &dag.cone[4 * size_t(v - dag.top_vertices)]);
      replay.collapse(v, onto, l, triangle_level, dag.remover);
    }
    replay.drop_level(m.triangle_count[l + 1], m.triangle_count[l]);
  }
  to_csr(pairs, dag.vertices, true, dag.prerequisite_offsets, dag.prerequisites);
  to_csr(pairs, dag.vertices, false, dag.dependent_offsets, dag.dependents);
  return dag;
}

}  // namespace pms
