// A multilevel mesh (gueziec et al. 1999) as the HTTP server offers it: the binary form cut into its HEAD
// and one resource per level, coarsest first, each with its strong ETag, and the same in the compressed
// form; built once, at start for a .pml file, on first request for one derived from a .pms
// (derived_multilevel.h; docs/protocol.md, "Multilevel over HTTP").
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "multilevel/mesh.h"

namespace pms::server {

struct ServedMultilevel {
  std::string name;  // file name without .pml
  std::string path;
  // The content version its URLs carry (docs/protocol.md, "Versions"): a derived mesh's is its .pms
  // model's, a .pml file's a hash of its levels.
  std::string version;
  uint32_t dimension = 3;
  bool normals = false, colors = false, texcoords = false;
  uint32_t vertices = 0, triangles = 0;
  std::shared_ptr<const std::vector<uint8_t>> head;  // the HEAD section
  std::string head_etag;
  // Per level, index = the level (0 finest): its LEVL section, ETag, and its LOD's size and error.
  std::vector<std::shared_ptr<const std::vector<uint8_t>>> levels;
  std::vector<std::string> level_etags;
  // The compressed form (multilevel/codec.h): its head and levels, indexed likewise.
  uint32_t position_bits = 0;
  std::shared_ptr<const std::vector<uint8_t>> compressed_head;
  std::string compressed_head_etag;
  std::vector<std::shared_ptr<const std::vector<uint8_t>>> compressed_levels;
  std::vector<std::string> compressed_level_etags;
  std::vector<uint32_t> lod_vertices, lod_triangles;
  std::vector<float> level_errors;  // multilevel_level_errors: what a screen-size rule projects
  std::array<float, 3> center{};    // bounding sphere of every vertex (the box's centre)
  float radius = 0;
  uint32_t level_count() const { return uint32_t(levels.size()); }
  uint64_t memory_bytes() const;  // the resources' bytes
};

// Reads either form (multilevel/file.h); pms::Error naming the file.
std::unique_ptr<ServedMultilevel> open_multilevel(const std::string& path);
// `mesh` cut into its resources under /models/{name}/{version}; an empty `version` is the mesh's own hash.
std::unique_ptr<ServedMultilevel> serve_multilevel(const MultilevelMesh& mesh, const std::string& name,
                                                   const std::string& path, const std::string& version = {});

}  // namespace pms::server
