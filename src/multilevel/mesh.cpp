// Progressive multilevel meshes: the structure's checks and LOD access (gueziec, taubin, horn, lazarus
// 1999, "Progressive multilevel mesh", "Support for smooth transitions"; path compression as in Tarjan).
#include "multilevel/mesh.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/error.h"

namespace pms {
namespace {

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;

std::string str(uint64_t v) { return std::to_string(v); }

// The secondary arrays: one per level or none, none at level 0, each naming vertices of its LOD in
// ascending order with finite values of the mesh's attributes.
void check_changed(const std::string& where, const MultilevelMesh& m) {
  if (m.changed.empty()) return;
  if (m.changed.size() != m.level_count())
    fail(where, str(m.changed.size()) + " secondary arrays for " + str(m.level_count()) + " levels");
  if (!m.changed[0].empty()) fail(where, "a secondary array at level 0, whose LOD is the primary arrays");
  for (uint32_t l = 1; l < m.level_count(); ++l) {
    const ChangedVertices& c = m.changed[l];
    const std::string name = "the secondary array of level " + str(l);
    const size_t n = c.size();
    if (c.positions.size() != n * m.dimension || c.normals.size() != (m.normals.empty() ? 0 : 3 * n) ||
        c.colors.size() != (m.colors.empty() ? 0 : 4 * n))
      fail(where, name + ": its values do not match its " + str(n) + " vertices and the mesh's attributes");
    for (size_t i = 0; i < n; ++i) {
      if (c.vertex[i] >= m.vertex_count[l])
        fail(where, name + " changes vertex " + str(c.vertex[i]) + ", which is not in LOD " + str(l));
      if (i > 0 && c.vertex[i] <= c.vertex[i - 1]) fail(where, name + ": its vertices are not strictly ascending");
    }
    for (float p : c.positions)
      if (!std::isfinite(p)) fail(where, name + ": a position is not finite");
    for (float p : c.normals)
      if (!std::isfinite(p)) fail(where, name + ": a normal is not finite");
  }
}

void check_sizes(const std::string& where, const MultilevelMesh& m) {
  if (m.dimension < 2 || m.dimension > 3) fail(where, "dimension " + str(m.dimension) + " (2 or 3 expected)");
  if (m.vertex_count.empty()) fail(where, "no levels");
  if (m.triangle_count.size() != m.vertex_count.size())
    fail(where, str(m.vertex_count.size()) + " vertex counts but " + str(m.triangle_count.size()) + " triangle counts");
  for (uint32_t l = 1; l < m.level_count(); ++l)
    if (m.vertex_count[l] > m.vertex_count[l - 1] || m.triangle_count[l] > m.triangle_count[l - 1])
      fail(where, "level " + str(l) + " has more vertices or triangles than level " + str(l - 1));
  const uint64_t n = m.vertices();
  if (m.positions.size() != n * m.dimension) fail(where, "positions do not match " + str(n) + " vertices");
  if (!m.normals.empty() && m.normals.size() != 3 * n) fail(where, "normals do not match " + str(n) + " vertices");
  if (!m.colors.empty() && m.colors.size() != 4 * n) fail(where, "colors do not match " + str(n) + " vertices");
  if (!m.texcoords.empty() && m.texcoords.size() != 2 * n)
    fail(where, "texture coordinates do not match " + str(n) + " vertices");
  if (m.representative.size() != n) fail(where, "representatives do not match " + str(n) + " vertices");
  if (m.triangles.size() != 3 * uint64_t(m.faces())) fail(where, "triangles do not match " + str(m.faces()));
  for (float p : m.positions)
    if (!std::isfinite(p)) fail(where, "a vertex position is not finite");
  for (float p : m.normals)
    if (!std::isfinite(p)) fail(where, "a vertex normal is not finite");
  for (float p : m.texcoords)
    if (!std::isfinite(p)) fail(where, "a vertex texture coordinate is not finite");
  check_changed(where, m);
}

// The level of triangle t: the highest l with t < triangle_count[l] (walked once, in order).
template <typename Fn>
void for_each_triangle_by_level(const MultilevelMesh& m, Fn&& fn) {
  for (uint32_t l = m.level_count(); l-- > 0;) {
    const uint32_t begin = l + 1 < m.level_count() ? m.triangle_count[l + 1] : 0;
    for (uint32_t t = begin; t < m.triangle_count[l]; ++t) fn(t, l);
  }
}

}  // namespace

uint64_t MultilevelMesh::stored_representatives() const {
  uint64_t count = 0;
  for (size_t v = 0; v < representative.size(); ++v) count += representative[v] != kNoRep;
  return count;
}

uint64_t MultilevelMesh::changed_vertices() const {
  uint64_t count = 0;
  for (const ChangedVertices& c : changed) count += c.size();
  return count;
}

uint32_t MultilevelMesh::level_vertices(uint32_t l) const {
  return vertex_count[l] - (l + 1 < level_count() ? vertex_count[l + 1] : 0);
}

uint32_t MultilevelMesh::level_triangles(uint32_t l) const {
  return triangle_count[l] - (l + 1 < level_count() ? triangle_count[l + 1] : 0);
}

void validate_multilevel(const std::string& where, const MultilevelMesh& m) {
  check_sizes(where, m);
  const uint32_t n = m.vertices();
  // Indices fall along a chain, so a chain reaches below n_l iff its root (last vertex) does.
  std::vector<uint32_t> root(n);
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t r = m.representative[v];
    if (r == kNoRep) {
      root[v] = v;
    } else {
      if (r >= v) fail(where, "vertex " + str(v) + " has representative " + str(r) + ", which is not below it");
      root[v] = root[r];
    }
  }
  for_each_triangle_by_level(m, [&](uint32_t t, uint32_t l) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.triangles[3 * size_t(t) + k];
      if (v >= n) fail(where, "triangle " + str(t) + " names vertex " + str(v) + " of " + str(n));
      if (v >= m.vertex_count[l] && root[v] >= m.vertex_count[l])
        fail(where, "triangle " + str(t) + " of level " + str(l) + " names vertex " + str(v) +
                        ", which is missing from that level and has no representative in it");
    }
  });
}

void representatives_stated_by(const MultilevelMesh& m, uint32_t t, uint32_t n_l, std::vector<uint8_t>& stated,
                               std::vector<uint32_t>& out) {
  for (int k = 0; k < 3; ++k) {
    for (uint32_t v = m.triangles[3 * size_t(t) + k]; v >= n_l && !stated[v];) {
      const uint32_t r = m.representative[v];
      if (r == kNoRep) break;  // validate_multilevel() rules this out
      stated[v] = 1;
      out.push_back(v);
      out.push_back(r);
      v = r;
    }
  }
}

std::vector<uint32_t> level_representatives(const MultilevelMesh& m, uint32_t level, std::vector<uint8_t>& stated) {
  const uint32_t t_end = m.triangle_count[level], t_begin = t_end - m.level_triangles(level);
  std::vector<uint32_t> reps;
  for (uint32_t t = t_begin; t < t_end; ++t) representatives_stated_by(m, t, m.vertex_count[level], stated, reps);
  // The coarser levels' triangles, the only ones that could state these, have been taken.
  const uint32_t v_end = m.vertex_count[level];
  for (uint32_t v = v_end - m.level_vertices(level); v < v_end; ++v)
    if (m.representative[v] != kNoRep && !stated[v]) {
      stated[v] = 1;
      reps.insert(reps.end(), {v, m.representative[v]});
    }
  return reps;
}

namespace {

// Per level, the representatives its triangles state; `stated` flags their vertices.
std::vector<uint32_t> count_stated(const MultilevelMesh& m, std::vector<uint8_t>& stated) {
  std::vector<uint32_t> count(m.level_count(), 0);
  stated.assign(m.vertices(), 0);
  std::vector<uint32_t> reps;
  for_each_triangle_by_level(m, [&](uint32_t t, uint32_t l) {
    reps.clear();
    representatives_stated_by(m, t, m.vertex_count[l], stated, reps);
    count[l] += uint32_t(reps.size() / 2);
  });
  return count;
}

}  // namespace

std::vector<uint32_t> representatives_per_level(const MultilevelMesh& m) {
  std::vector<uint8_t> stated;
  return count_stated(m, stated);
}

std::vector<uint32_t> geomorph_representatives_per_level(const MultilevelMesh& m) {
  std::vector<uint8_t> stated;
  count_stated(m, stated);
  std::vector<uint32_t> count(m.level_count(), 0);
  for (uint32_t l = 0; l < m.level_count(); ++l) {
    const uint32_t v_end = m.vertex_count[l];
    for (uint32_t v = v_end - m.level_vertices(l); v < v_end; ++v)
      count[l] += m.representative[v] != kNoRep && !stated[v];
  }
  return count;
}

uint64_t geomorph_representative_count(const MultilevelMesh& m) {
  const std::vector<uint32_t> count = geomorph_representatives_per_level(m);
  return std::accumulate(count.begin(), count.end(), uint64_t(0));
}

std::vector<float> multilevel_level_errors(const MultilevelMesh& m) {
  std::vector<float> errors(m.level_count(), 0);
  std::vector<uint32_t> at(m.vertices());
  std::vector<float> shown;  // the LOD's positions of its vertices (its secondary array applied)
  const uint32_t d = m.dimension, n = m.vertices();
  for (uint32_t l = 1; l < m.level_count(); ++l) {
    const uint32_t n_l = m.vertex_count[l];
    shown.assign(m.positions.begin(), m.positions.begin() + size_t(n_l) * d);
    if (m.changes(l))
      for (size_t i = 0; i < m.changed[l].size(); ++i)
        std::copy_n(&m.changed[l].positions[i * d], d, &shown[size_t(m.changed[l].vertex[i]) * d]);
    double worst = 0;
    for (uint32_t v = n_l; v < n; ++v) {
      const uint32_t r = m.representative[v];
      at[v] = r == kNoRep || r < n_l ? r : at[r];
      if (at[v] == kNoRep) continue;
      double sq = 0;
      for (uint32_t k = 0; k < d; ++k) {
        const double delta = double(m.positions[size_t(v) * d + k]) - shown[size_t(at[v]) * d + k];
        sq += delta * delta;
      }
      worst = std::max(worst, sq);
    }
    errors[l] = float(std::sqrt(worst));
  }
  return errors;
}

MultilevelLod::MultilevelLod(const MultilevelMesh& mesh) : mesh_(mesh) {}

// A coarse LOD has few triangles but many vertices above n_l: following each corner's chain costs less
// than the path-compressed copy, whose reads land all over the array. The walk gives up (and the copy is
// made) once it has taken as many steps as the copy would, so a level costs at most twice the copy.
bool MultilevelLod::connect_by_walking(uint32_t level) {
  const MultilevelMesh& m = mesh_;
  const uint32_t n_l = m.vertex_count[level], n = uint32_t(m.representative.size());
  const uint32_t corners = 3 * m.triangle_count[level];
  uint64_t budget = n - n_l;
  if (corners > budget) return false;
  budget -= corners;
  indices_.resize(corners);
  const uint32_t* tri = m.triangles.data();
  return m.representative.visit([&](auto representative) {
    for (uint32_t c = 0; c < corners; ++c) {
      uint32_t v = tri[c];
      while (v >= n_l) {
        if (budget-- == 0) return false;
        v = representative[v];  // never kNoRep: every corner of the LOD resolves (validate_multilevel)
      }
      indices_[c] = v;
    }
    return true;
  });
}

void MultilevelLod::connect(uint32_t level) {
  if (level == connected_) return;
  const MultilevelMesh& m = mesh_;
  // Up to every vertex the representatives cover: while levels are loading, the loaded triangles name
  // vertices of levels still to come (multilevel/loader.h).
  const uint32_t n_l = m.vertex_count[level], n = uint32_t(m.representative.size());
  connected_ = level;
  vertex_count_ = n_l;
  if (connect_by_walking(level)) return;
  // The copy is path-compressed against n_l in one pass: a representative is below its vertex, so it was
  // compressed before it.
  pc_rep_.resize(n);
  m.representative.visit([&](auto representative) {
    for (uint32_t v = n_l; v < n; ++v) {
      const uint32_t r = representative[v];
      pc_rep_[v] = r == kNoRep || r < n_l ? r : pc_rep_[r];
    }
  });
  const uint32_t corners = 3 * m.triangle_count[level];
  indices_.resize(corners);
  const uint32_t* tri = m.triangles.data();
  for (uint32_t c = 0; c < corners; ++c) {
    const uint32_t v = tri[c];
    indices_[c] = v < n_l ? v : pc_rep_[v];
  }
}

void MultilevelLod::set_level(uint32_t level) {
  level = std::min(level, mesh_.level_count() - 1);
  connect(level);
  own_values_ = mesh_.changes(level);
  if (own_values_) {
    values_at(level, shown_);
    morph_lo_ = morph_hi_ = 0xFFFFFFFFu;  // shown_ no longer holds a geomorph's start
  }
  level_ = float(level);
}

void MultilevelLod::values_at(uint32_t level, Values& out) const {
  const MultilevelMesh& m = mesh_;
  const uint32_t n = m.vertex_count[level], d = m.dimension;
  const auto prefix = [](const auto& all, auto& into, size_t count) {
    into.assign(all.begin(), all.begin() + (all.empty() ? 0 : count));
  };
  prefix(m.positions, out.positions, size_t(n) * d);
  prefix(m.normals, out.normals, size_t(n) * 3);
  prefix(m.colors, out.colors, size_t(n) * 4);
  prefix(m.texcoords, out.texcoords, size_t(n) * 2);
  if (!m.changes(level)) return;
  const ChangedVertices& c = m.changed[level];
  for (size_t i = 0; i < c.size(); ++i) {
    const uint32_t v = c.vertex[i];
    std::copy_n(&c.positions[i * d], d, &out.positions[size_t(v) * d]);
    if (!c.normals.empty()) std::copy_n(&c.normals[i * 3], 3, &out.normals[size_t(v) * 3]);
    if (!c.colors.empty()) std::copy_n(&c.colors[i * 4], 4, &out.colors[size_t(v) * 4]);
  }
}

void MultilevelLod::prepare_morph(uint32_t lo, uint32_t hi) {
  if (lo == morph_lo_ && hi == morph_hi_) return;
  const MultilevelMesh& m = mesh_;
  const uint32_t n_hi = m.vertex_count[hi], n_lo = m.vertex_count[lo];
  // Where each vertex of levels lo .. hi - 1 stands at level hi: its representative, followed while that is
  // still above n_hi (each is below its vertex, so it was placed before). One without a representative (a
  // structure with only the discrete LODs' representatives, e.g. read from the ASCII form) has no place
  // there and stays put.
  morph_source_.resize(n_lo - n_hi);
  m.representative.visit([&](auto representative) {
    for (uint32_t v = n_hi; v < n_lo; ++v) {
      const uint32_t r = representative[v];
      morph_source_[v - n_hi] = r == kNoRep ? v : r < n_hi ? r : morph_source_[r - n_hi];
    }
  });
  values_at(lo, morph_to_);
  values_at(hi, morph_from_);
  // A vertex of levels lo .. hi - 1 starts where LOD hi shows its source (one with none, where LOD lo shows it).
  const auto extend = [&](auto Values::*array, size_t width) {
    auto& from = morph_from_.*array;
    const auto& to = morph_to_.*array;
    if (to.empty()) return;
    from.resize(size_t(n_lo) * width);
    for (uint32_t v = n_hi; v < n_lo; ++v) {
      const uint32_t source = morph_source_[v - n_hi];
      const auto& values = source == v ? to : from;
      std::copy_n(&values[size_t(source) * width], width, &from[size_t(v) * width]);
    }
  };
  extend(&Values::positions, m.dimension);
  extend(&Values::normals, 3);
  extend(&Values::colors, 4);
  extend(&Values::texcoords, 2);
  shown_ = morph_to_;
  morph_lo_ = lo;
  morph_hi_ = hi;
}

void MultilevelLod::blend(float t, uint32_t begin, uint32_t end) {
  const uint32_t d = mesh_.dimension;
  const float s = 1 - t;
  const Values &from = morph_from_, &to = morph_to_;
  for (uint32_t v = begin; v < end; ++v) {
    for (uint32_t k = 0; k < d; ++k)
      shown_.positions[size_t(v) * d + k] = s * from.positions[size_t(v) * d + k] + t * to.positions[size_t(v) * d + k];
    if (!to.normals.empty()) {
      float nrm[3], len = 0;
      for (int k = 0; k < 3; ++k) {
        nrm[k] = s * from.normals[size_t(v) * 3 + k] + t * to.normals[size_t(v) * 3 + k];
        len += nrm[k] * nrm[k];
      }
      const float scale = len > 0 ? 1 / std::sqrt(len) : 0;
      for (int k = 0; k < 3; ++k)
        shown_.normals[size_t(v) * 3 + k] = len > 0 ? nrm[k] * scale : to.normals[size_t(v) * 3 + k];
    }
    for (size_t k = 0; k < (to.colors.empty() ? 0 : 4); ++k)
      shown_.colors[size_t(v) * 4 + k] =
          uint8_t(std::lround(s * from.colors[size_t(v) * 4 + k] + t * to.colors[size_t(v) * 4 + k]));
    for (size_t k = 0; k < (to.texcoords.empty() ? 0 : 2); ++k)
      shown_.texcoords[size_t(v) * 2 + k] = s * from.texcoords[size_t(v) * 2 + k] + t * to.texcoords[size_t(v) * 2 + k];
  }
}

void MultilevelLod::geomorph(uint32_t lo, float t) { geomorph(lo, lo + 1, t); }

void MultilevelLod::geomorph(uint32_t lo, uint32_t hi, float t) {
  const uint32_t top = mesh_.level_count() - 1;
  hi = std::min(hi, top);
  if (lo >= hi) {
    set_level(lo);
    return;
  }
  if (!(t >= 0)) t = 0;  // NaN too
  if (t > 1) t = 1;
  connect(lo);
  prepare_morph(lo, hi);
  // Without secondary arrays between them, the vertices of LOD hi stand at their own values in both.
  bool moved = false;
  for (uint32_t l = lo; l <= hi; ++l) moved = moved || mesh_.changes(l);
  blend(t, moved ? 0 : mesh_.vertex_count[hi], mesh_.vertex_count[lo]);
  own_values_ = true;
  level_ = float(hi) - float(hi - lo) * t;
}

void MultilevelLod::set_level(float x) {
  const uint32_t top = mesh_.level_count() - 1;
  if (!(x > 0)) x = 0;  // NaN too
  if (x >= float(top)) x = float(top);
  const uint32_t lo = uint32_t(std::floor(x));
  const float t = float(lo + 1) - x;  // 1 at x = lo: own positions; 0 at x = lo + 1: the representatives'
  if (lo == top || t >= 1) {
    set_level(lo);
    return;
  }
  geomorph(lo, t);
}

std::span<const float> MultilevelLod::positions() const {
  if (own_values_) return shown_.positions;
  return {mesh_.positions.data(), size_t(vertex_count_) * mesh_.dimension};
}

std::span<const float> MultilevelLod::normals() const {
  if (mesh_.normals.empty()) return {};
  if (own_values_) return shown_.normals;
  return {mesh_.normals.data(), size_t(vertex_count_) * 3};
}

std::span<const uint8_t> MultilevelLod::colors() const {
  if (mesh_.colors.empty()) return {};
  if (own_values_) return shown_.colors;
  return {mesh_.colors.data(), size_t(vertex_count_) * 4};
}

std::span<const float> MultilevelLod::texcoords() const {
  if (mesh_.texcoords.empty()) return {};
  if (own_values_) return shown_.texcoords;
  return {mesh_.texcoords.data(), size_t(vertex_count_) * 2};
}

Mesh lod_mesh(const MultilevelMesh& m, const MultilevelLod& lod) {
  Mesh out;
  const uint32_t n = lod.vertex_count(), d = m.dimension;
  const auto positions = lod.positions();
  out.positions.resize(size_t(n) * 3, 0.0f);  // a 2D file lies in z = 0
  for (uint32_t v = 0; v < n; ++v)
    for (uint32_t k = 0; k < d; ++k) out.positions[3 * size_t(v) + k] = positions[size_t(v) * d + k];
  out.normals.assign(lod.normals().begin(), lod.normals().end());
  out.colors.assign(lod.colors().begin(), lod.colors().end());
  out.texcoords.assign(lod.texcoords().begin(), lod.texcoords().end());
  out.indices.assign(lod.indices().begin(), lod.indices().end());
  return out;
}

}  // namespace pms
