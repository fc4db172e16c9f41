// Progressive loading of a multilevel mesh (gueziec et al. 1999, "Progressive multilevel mesh": a level is
// usable as soon as it is complete): the binary form's HEAD, then its LEVL sections coarsest first, each
// added to the structure on arrival (the paper's addLevel). The file reader and the HTTP client
// (docs/protocol.md, "Multilevel over HTTP") both load through it.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "multilevel/file.h"
#include "multilevel/level_neighbours.h"
#include "multilevel/mesh.h"
#include "spm/position_grid.h"

namespace pms {

// The binary form in the pieces a client loads one after another: the HEAD section's 32 bytes, then
// each level's LEVL section, coarsest first (levels[0] is level level_count - 1).
struct MultilevelParts {
  std::vector<uint8_t> head;
  std::vector<std::vector<uint8_t>> levels;
};
MultilevelParts multilevel_parts(const MultilevelMesh& mesh);

// While levels are missing, mesh() is the structure of the levels loaded: the finer levels have no vertex
// or triangle of their own yet (their counts are the finest loaded level's), so any LOD can be taken and a
// missing one is the finest loaded; `representative` already covers every vertex of the whole mesh, as the
// loaded triangles name vertices of levels still to come. Everything a peer sends is hostile: the head's
// totals are bounded by limits.max_file_bytes (the bytes the whole mesh would take), and each level is
// checked before it is kept, so that every LOD of what is loaded resolves.
// The binary form's levels, or the compressed form's (multilevel/codec.h), which a loader decodes
// into the LEVL section each stands for.
enum class MultilevelForm { plain, compressed };

class MultilevelLoader {
 public:
  // pms::Error "WHERE: what" for a head that is not one: the HEAD section, or the compressed head.
  MultilevelLoader(const std::string& where, std::span<const uint8_t> head, const MultilevelLimits& limits = {},
                   MultilevelForm form = MultilevelForm::plain);

  // addLevel: the LEVL section (or compressed level) of next_level(). `offset` is where the section starts
  // in what it came in, for the errors about its layout ("WHERE: offset N: section LEVL of level L: ...").
  // On an error the loader is unchanged only up to the level's own arrays: discard it.
  void add_level(const std::string& where, std::span<const uint8_t> section, uint64_t offset = 0);

  uint32_t level_count() const { return mesh_.level_count(); }
  uint32_t levels_loaded() const { return loaded_; }
  bool complete() const { return loaded_ == mesh_.level_count(); }
  uint32_t next_level() const { return mesh_.level_count() - 1 - loaded_; }  // only while !complete()
  uint32_t finest_loaded() const { return mesh_.level_count() - loaded_; }   // level_count() before the first
  const MultilevelMesh& mesh() const { return mesh_; }
  // The whole mesh once complete() (validated by the last add_level); the loader is left empty.
  MultilevelMesh release() { return std::move(mesh_); }

 private:
  void add_plain_level(const std::string& where, std::span<const uint8_t> section, uint64_t offset);
  void read_compressed_head(const std::string& where, std::span<const uint8_t> head);
  void take_changed(const std::string& where, uint32_t level, uint32_t n_l, uint32_t count, const uint8_t*& p);
  void take_representatives(const std::string& where, std::span<const uint32_t> pairs);
  void check_level_triangles(const std::string& where, uint32_t t_begin, uint32_t n_l);

  MultilevelMesh mesh_;
  uint32_t flags_ = 0;
  uint32_t total_vertices_ = 0, total_triangles_ = 0, total_representatives_ = 0, representatives_ = 0;
  uint32_t total_changed_ = 0, changed_ = 0;  // secondary array entries: HEAD's total, loaded
  uint32_t loaded_ = 0;
  std::vector<uint8_t> resolved_;  // per vertex: its chain is known to reach a loaded vertex
  MultilevelForm form_;
  PositionGrid grid_;                // the compressed form's
  PositionGrid texcoord_grid_;       // the compressed form's, when it has texture coordinates (z unused)
  CompressedLevelState compressed_;  // the compressed form's: what its levels are coded against
};

}  // namespace pms
