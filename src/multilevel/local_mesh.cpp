// The mesh of a local refinement (gueziec et al. 1999, Fig. 15): faces by the representatives of the
// chosen vertex set. A triangle is there when the collapse that removed it is undone; its corners follow
// representatives to the first vertex that is in, as a uniform LOD's corners follow them below n_l.
#include <algorithm>

#include "common/error.h"
#include "multilevel/local.h"

namespace pms {
namespace {

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;

// The finest l whose whole LOD is in: every vertex below n_l split or top-level.
uint32_t finest_whole_level(const MultilevelMesh& m, std::span<const uint8_t> in) {
  const uint32_t first_out = uint32_t(std::find(in.begin(), in.end(), uint8_t(0)) - in.begin());
  uint32_t l = 0;
  while (m.vertex_count[l] > first_out) ++l;  // the top level's n_l is the top vertex count, all in
  return l;
}

}  // namespace

LocalMesh local_mesh(const MultilevelMesh& m, const MultilevelDag& dag, const MultilevelRefinement& refinement) {
  const std::span<const uint8_t> in = refinement.split_flags();
  const uint32_t whole = finest_whole_level(m, in);
  LocalMesh out;
  std::vector<uint32_t> new_index(m.vertices(), kNoRep);
  for (uint32_t v = 0; v < m.vertices(); ++v)
    if (in[v]) {
      new_index[v] = uint32_t(out.vertex.size());
      out.vertex.push_back(v);
    }
  const uint32_t d = m.dimension;
  out.mesh.positions.assign(out.vertex.size() * 3, 0.0f);  // a 2D file lies in z = 0
  for (size_t i = 0; i < out.vertex.size(); ++i) {
    const uint32_t v = out.vertex[i];
    std::copy_n(&m.positions[size_t(v) * d], d, &out.mesh.positions[3 * i]);
    if (!m.normals.empty())
      out.mesh.normals.insert(out.mesh.normals.end(), &m.normals[3 * size_t(v)], &m.normals[3 * size_t(v)] + 3);
    if (!m.colors.empty())
      out.mesh.colors.insert(out.mesh.colors.end(), &m.colors[4 * size_t(v)], &m.colors[4 * size_t(v)] + 4);
    if (!m.texcoords.empty())
      out.mesh.texcoords.insert(out.mesh.texcoords.end(), &m.texcoords[2 * size_t(v)], &m.texcoords[2 * size_t(v)] + 2);
  }
  for (uint32_t l = m.level_count(); l-- > 0;) {
    const uint32_t begin = l + 1 < m.level_count() ? m.triangle_count[l + 1] : 0;
    for (uint32_t t = begin; t < m.triangle_count[l]; ++t) {
      const uint32_t r = dag.remover[t];
      if (r == MultilevelDag::kNoRemover ? l < whole : !in[r]) continue;
      for (int k = 0; k < 3; ++k) {
        uint32_t v = m.triangles[3 * size_t(t) + k];
        while (v != kNoRep && !in[v]) v = m.representative[v];
        if (v == kNoRep)
          fail("local refinement",
               "triangle " + std::to_string(t) + " has a corner with no representative in the mesh");
        out.mesh.indices.push_back(new_index[v]);
      }
    }
  }
  return out;
}

}  // namespace pms
