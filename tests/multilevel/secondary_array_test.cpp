// The secondary array (gueziec et al. 1999, "Progressive multilevel mesh": the positions and properties of
// a coarser LOD's vertices read from a secondary array): a clustered LOD shows its vertices at their
// clusters' positions with their members' mean normal and colour, closer to the input than the preferred
// ancestors' own; geomorphs run between the LODs' own values; both file forms and the compressed levels
// carry it exactly (on the grid for the latter); a loader refuses hostile ones by name.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "common/error.h"
#include "error_of.h"
#include "expect.h"
#include "io/shapes.h"
#include "multilevel/binary_internal.h"
#include "multilevel/cluster.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"

namespace pms {
namespace {

using test::error_of;

// A torus with normals and colours, clustered by nested grids (each cell of a coarse grid is a union of
// cells of the finer ones, so a cluster's members are its cell's input vertices).
Mesh coloured_torus() {
  constexpr float kR = 2.0f;
  Mesh mesh = make_torus(48, 24, kR, 0.5f);
  mesh.normals.resize(3 * mesh.vertex_count());
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {  // away from the tube's centre line
    const float* p = &mesh.positions[3 * v];
    const float ring = std::sqrt(p[0] * p[0] + p[1] * p[1]);
    const float n[3] = {p[0] - kR * p[0] / ring, p[1] - kR * p[1] / ring, p[2]};
    const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k) mesh.normals[3 * v + k] = n[k] / length;
  }
  mesh.colors.resize(4 * mesh.vertex_count());
  for (size_t v = 0; v < mesh.vertex_count(); ++v)
    for (int k = 0; k < 4; ++k) mesh.colors[4 * v + k] = uint8_t((v * (k + 3) * 37) % 256);
  return mesh;
}

MultilevelMesh clustered(const Mesh& mesh) {
  return build_multilevel_from_clusterings(mesh, grid_clusterings(mesh, std::vector<uint32_t>{16, 8, 4}));
}

// The squared distance of every input vertex to where LOD l shows the vertex it stands at, summed.
double stand_in_error(const MultilevelMesh& m, uint32_t l) {
  MultilevelLod lod(m);
  lod.set_level(l);
  const auto shown = lod.positions();
  const uint32_t n_l = m.vertex_count[l];
  constexpr uint32_t kNo = MultilevelMesh::kNoRepresentative;
  std::vector<uint32_t> at(m.vertices());
  double sum = 0;
  for (uint32_t v = 0; v < m.vertices(); ++v) {
    // Only the representatives the LODs' triangles need are stored: a vertex with none stands nowhere.
    const uint32_t r = m.representative[v];
    at[v] = v < n_l ? v : r == kNo ? kNo : at[r];
    if (at[v] == kNo) continue;
    for (int k = 0; k < 3; ++k) {
      const double d = double(m.positions[3 * size_t(v) + k]) - shown[3 * size_t(at[v]) + k];
      sum += d * d;
    }
  }
  return sum;
}

TEST(MultilevelSecondaryArray, AClusteredLodStandsAtItsClustersAndNearerTheInput) {
  const Mesh mesh = coloured_torus();
  const MultilevelMesh m = clustered(mesh);
  validate_multilevel("torus", m);
  ASSERT_EQ(m.changed.size(), m.level_count());
  EXPECT_TRUE(m.changed[0].empty());
  MultilevelMesh primary_only = m;
  primary_only.changed.clear();
  for (uint32_t l = 1; l < m.level_count(); ++l) {
    SCOPED_TRACE("level " + std::to_string(l));
    const ChangedVertices& c = m.changed[l];
    ASSERT_GT(c.size(), 0u);
    MultilevelLod lod(m);
    lod.set_level(l);
    for (size_t i = 0; i < c.size(); ++i) {
      const uint32_t v = c.vertex[i];
      ASSERT_LT(v, m.vertex_count[l]);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(lod.positions()[3 * size_t(v) + k], c.positions[3 * i + k]);
      for (int k = 0; k < 4; ++k) EXPECT_EQ(lod.colors()[4 * size_t(v) + k], c.colors[4 * i + k]);
      float length = 0;
      for (int k = 0; k < 3; ++k) length += lod.normals()[3 * size_t(v) + k] * lod.normals()[3 * size_t(v) + k];
      EXPECT_NEAR(length, 1, 1e-5);
    }
    // The centroid is the point nearest its members in the squared sense: every LOD is nearer the input.
    EXPECT_LT(stand_in_error(m, l), stand_in_error(primary_only, l));
    EXPECT_LE(multilevel_level_errors(m)[l], 2 * multilevel_level_errors(primary_only)[l]);
  }
  MultilevelLod finest(m);
  finest.set_level(0u);
  EXPECT_TRUE(std::equal(finest.positions().begin(), finest.positions().end(), m.positions.begin()))
      << "LOD 0 is the primary array";
}

TEST(MultilevelSecondaryArray, AGeomorphRunsFromTheCoarseLodsValuesToTheFineOnes) {
  const MultilevelMesh m = clustered(coloured_torus());
  const uint32_t top = m.level_count() - 1;
  for (uint32_t lo = 0; lo < top; ++lo)
    for (uint32_t hi = lo + 1; hi <= top; ++hi) {
      SCOPED_TRACE("geomorph " + std::to_string(lo) + " -> " + std::to_string(hi));
      MultilevelLod at_lo(m), at_hi(m), morph(m);
      at_lo.set_level(lo);
      at_hi.set_level(hi);
      morph.geomorph(lo, hi, 1);
      EXPECT_TRUE(std::equal(morph.positions().begin(), morph.positions().end(), at_lo.positions().begin(),
                             at_lo.positions().end()));
      morph.geomorph(lo, hi, 0);
      // At t = 0 every vertex of LOD lo stands where LOD hi shows it (a vertex of LOD hi at its own value there).
      const uint32_t n_hi = m.vertex_count[hi];
      for (uint32_t v = 0; v < n_hi; ++v)
        for (int k = 0; k < 3; ++k)
          ASSERT_EQ(morph.positions()[3 * size_t(v) + k], at_hi.positions()[3 * size_t(v) + k]) << "vertex " << v;
    }
}

TEST(MultilevelSecondaryArray, TheFileFormsAndTheCompressedLevelsCarryIt) {
  const MultilevelMesh m = clustered(coloured_torus());
  ASSERT_GT(m.changed_vertices(), 0u);
  test::expect_same_multilevel(parse_multilevel_binary("torus.pml", format_multilevel_binary(m)), m);
  const MultilevelParts parts = multilevel_compressed_parts(m, kDefaultPositionBits);
  MultilevelLoader loader("torus", parts.head, {}, MultilevelForm::compressed);
  for (const auto& level : parts.levels) loader.add_level("torus", level);
  ASSERT_TRUE(loader.complete());
  test::expect_same_multilevel(loader.release(), snapped_multilevel(m, kDefaultPositionBits));
  // The paper's ASCII form has no place for it: the LODs read back show their vertices at their own values.
  EXPECT_TRUE(parse_multilevel_ascii("torus.txt", format_multilevel_ascii(m)).changed.empty());
}

// The binary form's LEVL sections, one per level, coarsest first.
std::vector<std::vector<uint8_t>> plain_levels(const MultilevelMesh& m) { return multilevel_parts(m).levels; }

TEST(MultilevelSecondaryArray, HostileSecondaryArraysAreRefusedByName) {
  const MultilevelMesh m = clustered(coloured_torus());
  const MultilevelParts parts = multilevel_parts(m);
  const uint32_t top = m.level_count() - 1;
  // The coarsest level's section: its count word follows the representatives, the entries follow it.
  const auto load_coarsest = [&](const std::vector<uint8_t>& section) {
    return error_of([&] {
      MultilevelLoader loader("h", parts.head);
      loader.add_level("h", section);
    });
  };
  const std::vector<uint8_t>& coarsest = parts.levels[0];
  const ChangedVertices& c = m.changed[top];
  ASSERT_GE(c.size(), 2u);
  const size_t entries_bytes = c.size() * 4 * (1 + 3 + 3 + 1);
  const size_t first_vertex = coarsest.size() - entries_bytes;
  EXPECT_EQ(load_coarsest(coarsest), "");
  {
    std::vector<uint8_t> out_of_lod = coarsest;
    const uint32_t beyond = m.vertex_count[top];
    std::memcpy(&out_of_lod[first_vertex + 4 * (c.size() - 1)], &beyond, 4);
    EXPECT_NE(load_coarsest(out_of_lod).find("is not in its LOD or not in ascending order"), std::string::npos);
  }
  {
    std::vector<uint8_t> descending = coarsest;
    std::memcpy(&descending[first_vertex], &c.vertex[1], 4);
    std::memcpy(&descending[first_vertex + 4], &c.vertex[0], 4);
    EXPECT_NE(load_coarsest(descending).find("not in ascending order"), std::string::npos);
  }
  {
    std::vector<uint8_t> not_finite = coarsest;
    const float nan = std::nanf("");
    std::memcpy(&not_finite[first_vertex + 4 * c.size()], &nan, 4);
    EXPECT_NE(load_coarsest(not_finite).find("a position is not finite"), std::string::npos);
  }
  {
    std::vector<uint8_t> too_many = coarsest;
    const uint32_t count = uint32_t(m.changed_vertices()) + 1;
    std::memcpy(&too_many[first_vertex - 4], &count, 4);
    EXPECT_NE(load_coarsest(too_many).find("more secondary array entries than HEAD's total"), std::string::npos);
  }
  {
    std::vector<uint8_t> head = parts.head;
    multilevel_binary::HeadSection h;
    std::memcpy(&h, head.data(), sizeof h);
    h.flags &= ~multilevel_binary::kHasChanged;
    std::memcpy(head.data(), &h, sizeof h);
    EXPECT_NE(error_of([&] { MultilevelLoader("h", head); }).find("secondary array entries without the flag"),
              std::string::npos);
  }
  EXPECT_EQ(plain_levels(m).size(), m.level_count());
}

}  // namespace
}  // namespace pms
