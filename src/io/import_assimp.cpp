// Formats without a hand-written path (STL, glTF/GLB, FBX, ...) go through assimp. All meshes of
// the scene are merged with their node transforms applied, so a mesh instanced by two nodes gives
// two copies; point and line primitives are dropped. Normals, colours (set 0) and texture coordinates
// (set 0: glTF's TEXCOORD_0, as u v with v up, the convention assimp hands every format over in) are kept
// when every merged mesh has them.
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <utility>
#include <vector>

#include "common/error.h"
#include "io/import_internal.h"

namespace pms {

namespace {

struct Merge {
  const std::string& name;
  Mesh mesh;
  bool every_mesh_has_normals = true;
  bool every_mesh_has_colors = true;
  bool every_mesh_has_texcoords = true;

  // Appends the triangles of `source` placed by `transform`; vertices of a mesh without
  // triangles are not added at all.
  void append(const aiMesh& source, const aiMatrix4x4& transform) {
    if (!(source.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;
    const uint64_t base = mesh.vertex_count();
    if (base + source.mNumVertices > UINT32_MAX) fail(name, "more than 2^32 vertices after merging the scene");
    // Normals transform by the inverse transpose, so non-uniform scales keep them perpendicular.
    aiMatrix3x3 normal_transform(transform);
    normal_transform.Inverse().Transpose();
    every_mesh_has_normals &= source.HasNormals();
    every_mesh_has_colors &= source.HasVertexColors(0);
    every_mesh_has_texcoords &= source.HasTextureCoords(0);
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D p = transform * source.mVertices[v];
      mesh.positions.insert(mesh.positions.end(), {p.x, p.y, p.z});
      if (every_mesh_has_normals) {
        const aiVector3D n = (normal_transform * source.mNormals[v]).NormalizeSafe();
        mesh.normals.insert(mesh.normals.end(), {n.x, n.y, n.z});
      }
      if (every_mesh_has_colors) {
        const aiColor4D& c = source.mColors[0][v];
        mesh.colors.insert(mesh.colors.end(), {color_channel(c.r, true), color_channel(c.g, true),
                                               color_channel(c.b, true), color_channel(c.a, true)});
      }
      if (every_mesh_has_texcoords) {
        const aiVector3D& t = source.mTextureCoords[0][v];
        mesh.texcoords.insert(mesh.texcoords.end(), {t.x, t.y});
      }
    }
    for (unsigned f = 0; f < source.mNumFaces; ++f) {
      const aiFace& face = source.mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= source.mNumVertices) fail(name, "assimp returned a face index out of range");
        mesh.indices.push_back(uint32_t(base + face.mIndices[k]));
      }
    }
  }

  void finish() {
    if (!every_mesh_has_normals) mesh.normals = {};
    if (!every_mesh_has_colors) mesh.colors = {};
    if (!every_mesh_has_texcoords) mesh.texcoords = {};
  }
};

}  // namespace

Mesh import_assimp(const std::string& name, std::span<const uint8_t> data, const std::string& extension) {
  Assimp::Importer importer;
  if (extension.empty() || !importer.IsExtensionSupported("." + extension))
    fail(name,
         extension.empty() ? "no file extension to tell the mesh format" : "unknown mesh format '." + extension + "'");
  unsigned flags = aiProcess_Triangulate;
  if (extension == "stl") {
    // STL repeats every corner per triangle, each with the face normal; dropping the normals lets
    // JoinIdenticalVertices weld the corners into shared vertices.
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS);
    flags |= aiProcess_RemoveComponent | aiProcess_JoinIdenticalVertices;
  }
  const aiScene* scene = importer.ReadFileFromMemory(data.data(), data.size(), flags, extension.c_str());
  if (!scene || !scene->mRootNode) {
    std::string why = scene ? "the scene has no nodes" : importer.GetErrorString();
    std::replace_if(
        why.begin(), why.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
    fail(name, "cannot read as ." + extension + " (assimp: " + why + ")");
  }

  Merge merge{name, {}};
  // Depth-first over the node tree without recursion: a hostile file may nest nodes very deeply.
  std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{scene->mRootNode, scene->mRootNode->mTransformation}};
  while (!stack.empty()) {
    const auto [node, transform] = stack.back();
    stack.pop_back();
    for (unsigned m = 0; m < node->mNumMeshes; ++m)
      if (node->mMeshes[m] < scene->mNumMeshes) merge.append(*scene->mMeshes[node->mMeshes[m]], transform);
    for (unsigned c = 0; c < node->mNumChildren; ++c)
      stack.emplace_back(node->mChildren[c], transform * node->mChildren[c]->mTransformation);
  }
  merge.finish();
  return std::move(merge.mesh);
}

}  // namespace pms
