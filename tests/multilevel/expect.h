// Test-only: two multilevel structures are the same, array by array (gtest expectations).
#pragma once
#include <gtest/gtest.h>

#include "multilevel/mesh.h"

namespace pms::test {

inline void expect_same_multilevel(const MultilevelMesh& a, const MultilevelMesh& b) {
  EXPECT_EQ(a.dimension, b.dimension);
  EXPECT_EQ(a.vertex_count, b.vertex_count);
  EXPECT_EQ(a.triangle_count, b.triangle_count);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.texcoords, b.texcoords);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.representative, b.representative);
  ASSERT_EQ(a.changed.size(), b.changed.size());
  for (size_t l = 0; l < a.changed.size(); ++l) {
    EXPECT_EQ(a.changed[l].vertex, b.changed[l].vertex) << "secondary array of level " << l;
    EXPECT_EQ(a.changed[l].positions, b.changed[l].positions) << "secondary array of level " << l;
    EXPECT_EQ(a.changed[l].normals, b.changed[l].normals) << "secondary array of level " << l;
    EXPECT_EQ(a.changed[l].colors, b.changed[l].colors) << "secondary array of level " << l;
  }
}

}  // namespace pms::test
