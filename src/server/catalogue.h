// The models a server offers: memory-mapped .pms files and what every session shares of each, each mode's
// tables built once, when first needed.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/limits.h"
#include "server/model_tables.h"
#include "server/served_mode.h"
#include "server/served_multilevel.h"
#include "server/table_builds.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"

namespace pms::server {

// One model as every session sees it: the mapped file, the BASE frame encoded once, and each mode's tables
// (model_tables.h), built when a session first asks for that mode, or at start for the modes preloaded.
// Shared: a reload keeps an unchanged file's model, tables and all, in the next catalogue, and a table
// build holds the model it builds.
struct ServedModel : std::enable_shared_from_this<ServedModel> {
  std::string name;  // file name without .pms
  std::string path;
  // The content version every URL of the model carries (docs/protocol.md, "Versions"): a hash of the
  // file's content checksum, the wire's grid and the records format, so a file replaced under the same
  // name, or served on another grid, has other URLs and no cache holds a stale answer for one.
  std::string version;
  std::unique_ptr<PmsFile> file;
  protocol::ModelInfo info;
  protocol::StreamContext context;
  std::shared_ptr<const std::vector<uint8_t>> base_frame;
  std::unique_ptr<ModelTables> tables;
  // The receiver-driven answers' body format (server/split_records_body.h), part of every ETag: 4, the
  // compact records with canonical cut references and in-plane positions larger first (3 coded each axis
  // alone; 2 had no attribute section, and no normals or colors; 1 was VSPLITS packets), so a client of
  // another format is refused with its number, not a parse error.
  static constexpr uint32_t records_format = 4;
  const ModelData& model() const { return file->model(); }
};

// The version of a model file served on a grid of `grid_bits` (ServedModel::version).
std::string content_version(uint64_t content_checksum, uint32_t grid_bits);

// How a catalogue builds its models' tables: which modes at once, and how many builds may run at once.
struct TableOptions {
  ModeSet preload = streaming_modes();
  uint32_t max_builds = 2;
};

// What a reload changed, by model name; `skipped` names a file (or path) and why it is not served.
struct CatalogueChanges {
  std::vector<std::string> added, removed, replaced, kept, skipped;
  bool any() const { return !added.empty() || !removed.empty() || !replaced.empty(); }
};

class Catalogue {
 public:
  // Every FILE.pms given and every *.pms in the directories given, and likewise multilevel meshes (.pml,
  // served over HTTP only); throws pms::Error naming the file for an unreadable or corrupt model, or two
  // models with the same name.
  // The tables of `tables.preload` are built before it returns (pms::Error naming the model and mode for
  // one that fails), the others when first asked for.
  static std::shared_ptr<const Catalogue> open(const std::vector<std::string>& paths,
                                               uint32_t position_bits = protocol::kDefaultPositionBits,
                                               const TableOptions& tables = {});
  // The models `previous`'s paths hold now (SIGHUP; docs/operating.md, "Signals"), built aside while
  // `previous` serves on: a file whose content checksum is unchanged keeps previous's model (its mapping
  // and built tables); a new or changed one is opened, its preloaded modes queued on the same builders.
  // A path or file that fails to open, a name served twice and a model that breaks `limits` are skipped
  // and named in `changes`, the rest served. pms::Error when no model is left or the CATALOGUE breaks
  // `limits`: the caller keeps `previous`.
  static std::shared_ptr<const Catalogue> reload(const Catalogue& previous, const ServerLimits& limits,
                                                 CatalogueChanges& changes);
  const ServedModel* find(const std::string& name) const;
  const std::vector<std::shared_ptr<ServedModel>>& models() const { return models_; }
  const ServedMultilevel* find_multilevel(const std::string& name) const;
  const std::vector<std::shared_ptr<ServedMultilevel>>& multilevel_models() const { return multilevel_; }
  // The CATALOGUE frame, encoded once and shared by every LIST's answer.
  const std::shared_ptr<const std::vector<uint8_t>>& catalogue_frame() const { return catalogue_frame_; }
  uint64_t mapped_bytes() const;
  // The tables' workers: sessions and HTTP connections ask them for a mode's tables. One set for a
  // catalogue and every catalogue reloaded from it.
  TableBuilds& table_builds() const { return *builds_; }
  const std::shared_ptr<TableBuilds>& shared_table_builds() const { return builds_; }
  uint64_t table_bytes() const;  // every model's built tables
  // pms::Error naming the model when a frame the server would send can exceed limits.max_server_message
  // (a BASE, the CATALOGUE, a full VSPLITS batch), or the batch is too large to slice.
  void check_limits(const ServerLimits& limits) const;

 private:
  void finish();  // the CATALOGUE frame

  std::vector<std::string> paths_;
  uint32_t position_bits_ = protocol::kDefaultPositionBits;
  ModeSet preload_;
  // First: its workers stop after the last catalogue that shares them is gone; each build holds its model.
  std::shared_ptr<TableBuilds> builds_;
  std::vector<std::shared_ptr<ServedModel>> models_;
  std::vector<std::shared_ptr<ServedMultilevel>> multilevel_;
  std::shared_ptr<const std::vector<uint8_t>> catalogue_frame_;
};

}  // namespace pms::server
