// The models a server offers: memory-mapped .pms files and what every session shares of each, built once.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dag/dag.h"
#include "protocol/message_types.h"
#include "protocol/packet_table.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "protocol/stream_context.h"
#include "server/limits.h"
#include "server/selective_streaming.h"
#include "server/served_multilevel.h"
#include "spm/criteria.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"

namespace pms::server {

// One model as every session sees it: the mapped file, the BASE frame encoded once, and qrefine's
// inputs per node decoded once (positions snapped to the wire grid, so the server evaluates exactly
// the numbers its clients hold).
struct ServedModel {
  std::string name;  // file name without .pms
  std::string path;
  std::unique_ptr<PmsFile> file;
  protocol::ModelInfo info;
  protocol::StreamContext context;
  std::shared_ptr<const std::vector<uint8_t>> base_frame;
  std::vector<NodeCriteria> criteria;  // per node
  std::vector<uint32_t> split_rank;    // per node: its index in split_order (view-independent mode); leaves kNone
  DependencyFilter dependencies;
  // Sender-driven packets (with refinement info): v_s's id and its split record; the sessions get
  // `codec_frame` after BASE.
  protocol::PacketTable packets;
  std::unique_ptr<const Dag> dag;  // the DAG mode's operations, on the wire grid's positions
  // The receiver-driven answers' body format (server/split_records_body.h), part of every ETag: 4, the
  // compact records with canonical cut references and in-plane positions larger first (3 coded each axis
  // alone; 2 had no attribute section, and no normals or colors; 1 was VSPLITS packets), so a client of
  // another format is refused with its number, not a parse error.
  static constexpr uint32_t records_format = 4;
  protocol::StoredRecords records;  // the file's own at the served grid, or `own_records`
  EncodedRecords own_records;       // coded at load when the file's records are at another grid
  std::shared_ptr<const std::vector<uint8_t>> codec_tables;  // serialized (GET /models/{m}/codec)
  std::shared_ptr<const SplitCodec> codec;                   // the tables
  std::shared_ptr<const std::vector<uint8_t>> codec_frame;   // CODEC, the tables for a sender-driven session
  const ModelData& model() const { return file->model(); }
};

class Catalogue {
 public:
  // Every FILE.pms given and every *.pms in the directories given, and likewise multilevel meshes (.pml,
  // served over HTTP only); throws pms::Error naming the file for an unreadable or corrupt model, or two
  // models with the same name.
  static std::shared_ptr<const Catalogue> open(const std::vector<std::string>& paths,
                                               uint32_t position_bits = protocol::kDefaultPositionBits);
  const ServedModel* find(const std::string& name) const;
  const std::vector<std::unique_ptr<ServedModel>>& models() const { return models_; }
  const ServedMultilevel* find_multilevel(const std::string& name) const;
  const std::vector<std::unique_ptr<ServedMultilevel>>& multilevel_models() const { return multilevel_; }
  // The CATALOGUE frame, encoded once and shared by every LIST's answer.
  const std::shared_ptr<const std::vector<uint8_t>>& catalogue_frame() const { return catalogue_frame_; }
  uint64_t mapped_bytes() const;
  // pms::Error naming the model when a frame the server would send can exceed limits.max_server_message
  // (a BASE, the CATALOGUE, a full VSPLITS batch), or the batch is too large to slice.
  void check_limits(const ServerLimits& limits) const;

 private:
  std::vector<std::unique_ptr<ServedModel>> models_;
  std::vector<std::unique_ptr<ServedMultilevel>> multilevel_;
  std::shared_ptr<const std::vector<uint8_t>> catalogue_frame_;
};

}  // namespace pms::server
