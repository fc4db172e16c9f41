// Progressive multilevel meshes built from the builder's collapses (gueziec et al. 1999): every LOD is the
// mesh the collapses below its level make, jumps between levels equal stepwise ones, geomorph ends are the
// levels, merged levels are LODs of the unmerged mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <string>
#include <vector>

#include "fixtures/view_models.h"
#include "io/shapes.h"
#include "multilevel/build.h"
#include "multilevel/mesh.h"

namespace pms {
namespace {

using Corner = std::array<float, 3>;
using Face = std::array<Corner, 3>;

// Non-degenerate faces as position triples rotated to their smallest corner, sorted: equal for the same
// oriented faces whatever the numbering.
std::vector<Face> face_set(std::span<const float> positions, uint32_t dimension, std::span<const uint32_t> indices) {
  std::vector<Face> faces;
  for (size_t f = 0; f + 2 < indices.size(); f += 3) {
    const uint32_t a = indices[f], b = indices[f + 1], c = indices[f + 2];
    if (a == b || b == c || c == a) continue;
    Face face{};
    for (int k = 0; k < 3; ++k)
      for (uint32_t d = 0; d < dimension; ++d) face[k][d] = positions[size_t(indices[f + k]) * dimension + d];
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    faces.push_back(face);
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

// The reference: the input with every collapse of level < l applied in sequence order, independently of
// the multilevel structure (each removed vertex replaced by its survivor, chains followed).
std::vector<Face> collapsed_faces(const Mesh& mesh, std::span<const EdgeCollapse> collapses,
                                  const CollapseLevels& levels, uint32_t l) {
  std::vector<uint32_t> onto(mesh.vertex_count());
  for (uint32_t v = 0; v < onto.size(); ++v) onto[v] = v;
  for (const EdgeCollapse& c : collapses)
    if (levels.vertex_level[c.removed] < l) onto[c.removed] = c.survivor;
  std::vector<uint32_t> indices(mesh.indices.size());
  for (size_t i = 0; i < indices.size(); ++i) {
    uint32_t v = mesh.indices[i];
    while (onto[v] != v) v = onto[v];
    indices[i] = v;
  }
  return face_set(mesh.positions, 3, indices);
}

std::vector<Face> lod_faces(const MultilevelLod& lod, uint32_t dimension) {
  return face_set(lod.positions(), dimension, lod.indices());
}

void expect_every_level_is_its_collapses(const test::BuiltModel& model) {
  const std::vector<EdgeCollapse> collapses = collapses_of(model.h);
  const CollapseLevels levels = assign_levels(model.input, collapses);
  const MultilevelMesh ml = assemble_multilevel(model.input, levels, MultilevelRepresentatives::geomorph);
  validate_multilevel(model.name, ml);
  ASSERT_GT(ml.level_count(), 2u) << model.name;
  EXPECT_EQ(ml.vertices(), model.input.vertex_count());
  EXPECT_EQ(ml.vertex_count.back(), model.h.root_count) << "the top level is the base mesh";
  EXPECT_EQ(ml.triangle_count.back(), model.h.base_faces.size() / 3);
  MultilevelLod lod(ml);
  for (uint32_t l = 0; l < ml.level_count(); ++l) {
    lod.set_level(l);
    const std::vector<Face> faces = lod_faces(lod, 3);
    EXPECT_EQ(faces.size(), ml.triangle_count[l])
        << model.name << " level " << l << ": a triangle of the LOD degenerated";
    EXPECT_EQ(faces, collapsed_faces(model.input, collapses, levels, l)) << model.name << " level " << l;
  }
  // Level 0 is the input itself.
  lod.set_level(0u);
  EXPECT_EQ(lod_faces(lod, 3), face_set(model.input.positions, 3, model.input.indices));
  // Representatives are stored only for vertices that triangles of a coarser LOD reach.
  EXPECT_LT(ml.stored_representatives(), ml.vertices() - ml.vertex_count.back() + 1);
}

TEST(Multilevel, EveryLevelIsTheMeshOfItsCollapsesSphere) { expect_every_level_is_its_collapses(test::built_sphere()); }
TEST(Multilevel, EveryLevelIsTheMeshOfItsCollapsesTerrain) {
  expect_every_level_is_its_collapses(test::built_terrain());
}

TEST(Multilevel, EveryLevelIsTheMeshOfItsCollapsesBunny) {
  const test::BuiltModel* bunny = test::built_bunny();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  expect_every_level_is_its_collapses(*bunny);
}

TEST(Multilevel, JumpsInRandomOrderEqualStepwiseLevels) {
  const test::BuiltModel& model = test::built_terrain();
  const MultilevelMesh ml = build_multilevel(model.input, collapses_of(model.h));
  std::vector<std::vector<uint32_t>> stepwise;
  {
    MultilevelLod lod(ml);
    for (uint32_t l = 0; l < ml.level_count(); ++l) {
      lod.set_level(l);
      stepwise.emplace_back(lod.indices().begin(), lod.indices().end());
    }
  }
  MultilevelLod lod(ml);
  std::mt19937 rng(17);
  for (int i = 0; i < 200; ++i) {
    const uint32_t l = rng() % ml.level_count();
    lod.set_level(l);
    ASSERT_EQ(std::vector<uint32_t>(lod.indices().begin(), lod.indices().end()), stepwise[l]) << "jump to " << l;
    EXPECT_EQ(lod.vertex_count(), ml.vertex_count[l]);
    if (i % 7 == 0) lod.set_level(float(l) + 0.5f);  // a geomorph in between must not disturb the next jump
  }
}

TEST(Multilevel, GeomorphEndsAreTheLevels) {
  const test::BuiltModel& model = test::built_sphere();
  Mesh input = model.input;
  input.colors.assign(input.vertex_count() * 4, 0);
  for (size_t v = 0; v < input.vertex_count(); ++v)
    input.colors[4 * v] = uint8_t(v * 37), input.colors[4 * v + 3] = 255;
  const MultilevelMesh ml = build_multilevel(input, collapses_of(model.h));
  MultilevelLod lod(ml), exact(ml);
  for (uint32_t lo = 0; lo + 1 < ml.level_count(); ++lo) {
    // t = 1: the level itself, positions and colours.
    lod.geomorph(lo, 1);
    exact.set_level(lo);
    EXPECT_EQ(lod_faces(lod, 3), lod_faces(exact, 3)) << "t = 1, level " << lo;
    EXPECT_TRUE(std::equal(lod.colors().begin(), lod.colors().end(), exact.colors().begin()));
    // t = 0: LOD lo's connectivity with its own vertices on their representatives, which is LOD lo + 1 as
    // a surface (the triangles of level lo have collapsed to zero area).
    lod.geomorph(lo, 0);
    exact.set_level(lo + 1);
    std::vector<Face> visible;
    for (const Face& f : lod_faces(lod, 3))
      if (f[0] != f[1] && f[1] != f[2] && f[2] != f[0]) visible.push_back(f);
    EXPECT_EQ(visible, lod_faces(exact, 3)) << "t = 0, level " << lo;
    // Halfway: LOD lo's triangles, every vertex halfway between where t = 0 and t = 1 put it.
    lod.geomorph(lo, 0);
    const std::vector<float> start(lod.positions().begin(), lod.positions().end());
    lod.geomorph(lo, 1);
    const std::vector<float> end(lod.positions().begin(), lod.positions().end());
    lod.set_level(float(lo) + 0.5f);
    EXPECT_FLOAT_EQ(lod.level(), float(lo) + 0.5f);
    ASSERT_EQ(lod.positions().size(), start.size());
    size_t moving = 0;
    for (size_t i = 0; i < start.size(); ++i) {
      EXPECT_NEAR(lod.positions()[i], 0.5f * (start[i] + end[i]), 1e-5f) << "coordinate " << i;
      moving += start[i] != end[i];
    }
    EXPECT_GT(moving, 0u) << "level " << lo << " has vertices that move";
    EXPECT_EQ(lod.indices().size(), 3 * size_t(ml.triangle_count[lo]));
    EXPECT_EQ(lod.colors().size(), 4 * size_t(ml.vertex_count[lo]));
  }
}

// Exact ends of the geomorph between LOD lo and the coarser LOD hi: at t = 1 LOD lo itself; at t = 0 every
// triangle of levels lo .. hi - 1 has two corners at one position (zero area) and every triangle of LOD hi
// has each corner where LOD hi puts it (the same triangle index: LODs are prefixes), colours too. Bit for
// bit: t = 0 copies the representative's values.
void expect_exact_ends(const MultilevelMesh& ml, uint32_t lo, uint32_t hi, const std::string& name) {
  MultilevelLod lod(ml), exact(ml);
  lod.geomorph(lo, hi, 1);
  exact.set_level(lo);
  ASSERT_TRUE(std::ranges::equal(lod.indices(), exact.indices())) << name << ", t = 1, levels " << lo << "-" << hi;
  ASSERT_TRUE(std::ranges::equal(lod.positions(), exact.positions())) << name << ", t = 1, levels " << lo << "-" << hi;
  ASSERT_TRUE(std::ranges::equal(lod.colors(), exact.colors())) << name << ", t = 1, levels " << lo << "-" << hi;

  lod.geomorph(lo, hi, 0);
  EXPECT_EQ(lod.level(), float(hi));
  exact.set_level(hi);
  const auto at = [](const MultilevelLod& l, uint32_t v) {
    return Corner{l.positions()[3 * size_t(v)], l.positions()[3 * size_t(v) + 1], l.positions()[3 * size_t(v) + 2]};
  };
  const auto colour = [](const MultilevelLod& l, uint32_t v) {
    return std::array<uint8_t, 4>{l.colors()[4 * size_t(v)], l.colors()[4 * size_t(v) + 1],
                                  l.colors()[4 * size_t(v) + 2], l.colors()[4 * size_t(v) + 3]};
  };
  const uint32_t t_hi = ml.triangle_count[hi], t_lo = ml.triangle_count[lo];
  size_t flat = 0, wrong_corners = 0;
  for (uint32_t t = t_hi; t < t_lo; ++t) {
    const Corner a = at(lod, lod.indices()[3 * size_t(t)]), b = at(lod, lod.indices()[3 * size_t(t) + 1]),
                 c = at(lod, lod.indices()[3 * size_t(t) + 2]);
    flat += a == b || b == c || c == a;
  }
  for (uint32_t t = 0; t < t_hi; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = lod.indices()[3 * size_t(t) + k], w = exact.indices()[3 * size_t(t) + k];
      wrong_corners += at(lod, u) != at(exact, w) || colour(lod, u) != colour(exact, w);
    }
  EXPECT_EQ(flat, t_lo - t_hi) << name << ", t = 0, levels " << lo << "-" << hi << ": the finer triangles have zero area";
  EXPECT_EQ(wrong_corners, 0u) << name << ", t = 0, levels " << lo << "-" << hi << ": the rest are LOD " << hi << "'s";
}

// Every adjacent pair, merged or not, and switches across many levels: finest to coarsest, and from the
// middle both ways (one geomorph per switch, however far).
void expect_exact_geomorph_ends(const test::BuiltModel& model, uint32_t level_count) {
  Mesh input = model.input;
  input.colors.assign(input.vertex_count() * 4, 0);
  for (size_t v = 0; v < input.vertex_count(); ++v)
    input.colors[4 * v + 1] = uint8_t(v * 53), input.colors[4 * v + 3] = 255;
  const MultilevelMesh ml = build_multilevel(input, collapses_of(model.h), level_count);
  const std::string name = model.name + " " + std::to_string(ml.level_count()) + " levels";
  ASSERT_GT(ml.level_count(), 1u) << name;
  const uint32_t top = ml.level_count() - 1, middle = top / 2;
  for (uint32_t lo = 0; lo < top; ++lo) expect_exact_ends(ml, lo, lo + 1, name);
  expect_exact_ends(ml, 0, top, name);
  if (middle > 0) expect_exact_ends(ml, 0, middle, name);
  if (middle + 1 < top) expect_exact_ends(ml, middle, top, name);
}

TEST(Multilevel, GeomorphEndsAreTheLevelsMergedSphere) {
  for (uint32_t L : {0u, 2u, 3u, 6u, 8u}) expect_exact_geomorph_ends(test::built_sphere(), L);
}

TEST(Multilevel, GeomorphEndsAreTheLevelsMergedTerrain) {
  for (uint32_t L : {0u, 2u, 5u, 8u, 16u}) expect_exact_geomorph_ends(test::built_terrain(), L);
}

TEST(Multilevel, GeomorphEndsAreTheLevelsMergedBunny) {
  const test::BuiltModel* bunny = test::built_bunny();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  for (uint32_t L : {0u, 4u, 8u, 16u}) expect_exact_geomorph_ends(*bunny, L);
}

// The geomorph build is the discrete one plus representatives that no triangle states: the same arrays
// otherwise, every discrete representative kept, and the discrete one is valid without the extra ones.
TEST(Multilevel, GeomorphRepresentativesOnlyAddToTheDiscreteOnes) {
  const test::BuiltModel& model = test::built_terrain();
  const std::vector<EdgeCollapse> collapses = collapses_of(model.h);
  for (uint32_t L : {0u, 3u, 8u}) {
    const MultilevelMesh discrete = build_multilevel(model.input, collapses, L, MultilevelRepresentatives::discrete);
    const MultilevelMesh morph = build_multilevel(model.input, collapses, L, MultilevelRepresentatives::geomorph);
    EXPECT_EQ(morph.positions, discrete.positions);
    EXPECT_EQ(morph.triangles, discrete.triangles);
    EXPECT_EQ(morph.vertex_count, discrete.vertex_count);
    validate_multilevel("discrete", discrete);
    EXPECT_EQ(geomorph_representative_count(discrete), 0u) << L << " levels";
    for (uint32_t v = 0; v < morph.vertices(); ++v) {
      if (discrete.representative[v] != MultilevelMesh::kNoRepresentative) {
        ASSERT_EQ(morph.representative[v], discrete.representative[v]) << L << " levels, vertex " << v;
      }
    }
    EXPECT_EQ(morph.stored_representatives(), discrete.stored_representatives() + geomorph_representative_count(morph));
    EXPECT_EQ(representatives_per_level(morph), representatives_per_level(discrete));
    if (L == 8) {
      EXPECT_GT(geomorph_representative_count(morph), 0u) << "merged levels need some";
    }
  }
}

TEST(Multilevel, MergedLevelsAreLevelsOfTheUnmergedMesh) {
  const test::BuiltModel& model = test::built_terrain();
  const std::vector<EdgeCollapse> collapses = collapses_of(model.h);
  const MultilevelMesh full = build_multilevel(model.input, collapses);
  for (uint32_t L : {1u, 2u, 3u, 5u}) {
    const MultilevelMesh merged = build_multilevel(model.input, collapses, L);
    validate_multilevel("merged", merged);
    ASSERT_EQ(merged.level_count(), L);
    // The discrete LODs' representatives can only drop; a geomorph's cover at most the removed vertices.
    EXPECT_LE(
        build_multilevel(model.input, collapses, L, MultilevelRepresentatives::discrete).stored_representatives(),
        build_multilevel(model.input, collapses, 0, MultilevelRepresentatives::discrete).stored_representatives());
    EXPECT_LE(merged.stored_representatives(), merged.vertices() - merged.vertex_count.back());
    // Parents of a vertex's own merged level stay its representatives (multilevel/build.h).
    uint32_t own_level = 0;
    for (uint32_t l = 0; l + 1 < L; ++l)
      for (uint32_t v = merged.vertex_count[l + 1]; v < merged.vertex_count[l]; ++v)
        own_level += merged.representative[v] != MultilevelMesh::kNoRepresentative &&
                     merged.representative[v] >= merged.vertex_count[l + 1];
    if (L > 1) {
      EXPECT_GT(own_level, 0u) << L << " levels";
    }
    const std::vector<uint32_t> map = merge_level_map(full.level_count(), L);
    MultilevelLod a(merged), b(full);
    for (uint32_t m = 0; m < L; ++m) {
      const uint32_t k = uint32_t(std::find(map.begin(), map.end(), m) - map.begin());
      a.set_level(m);
      b.set_level(k);
      EXPECT_EQ(lod_faces(a, 3), lod_faces(b, 3)) << L << " levels, level " << m << " = level " << k;
    }
  }
}

TEST(Multilevel, CollapsesOnRemovedVerticesAreRefused) {
  const Mesh grid = make_grid(3, 3);
  const std::vector<EdgeCollapse> bad = {{0, 1}, {0, 2}};
  EXPECT_THROW(assign_levels(grid, bad), Error);
  const std::vector<EdgeCollapse> self = {{4, 4}};
  EXPECT_THROW(assign_levels(grid, self), Error);
  const std::vector<EdgeCollapse> out = {{0, 1000}};
  EXPECT_THROW(assign_levels(grid, out), Error);
}

// The paper's rule on a small strip: a collapse next to an earlier one's endpoints gets a higher level,
// one far from it shares the level.
TEST(Multilevel, LevelsFollowTheStarRule) {
  const Mesh grid = make_grid(6, 1);  // 7 x 2 vertices in a strip
  ASSERT_EQ(grid.vertex_count(), 14u);
  const std::vector<EdgeCollapse> collapses = {{0, 1}, {12, 13}, {1, 2}};
  const CollapseLevels levels = assign_levels(grid, collapses);
  EXPECT_EQ(levels.vertex_level[0], 0u);
  EXPECT_EQ(levels.vertex_level[12], 0u) << "its star does not touch the first collapse";
  EXPECT_EQ(levels.vertex_level[1], 1u) << "1 is an endpoint of the first collapse";
  EXPECT_EQ(levels.level_count, 3u);
  EXPECT_EQ(levels.vertex_level[2], 2u) << "survivors take the top level";
}

}  // namespace
}  // namespace pms
