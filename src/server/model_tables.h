// What a served model builds per streaming mode, the first time a session asks for that mode (or at start
// with `serve --preload`): the pieces the modes share, each built once, and each mode's state. The builds
// run on TableBuilds' workers (table_builds.h), which alone change a state.
#pragma once
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "dag/dag.h"
#include "protocol/packet_table.h"
#include "protocol/split_bands.h"
#include "server/selective_streaming.h"
#include "server/served_mode.h"
#include "server/served_multilevel.h"
#include "spm/criteria.h"
#include "spm/split_codec.h"

namespace pms::server {

struct ServedModel;

// qrefine's inputs per node on the wire's positions, and the dependency filter: what the sender-driven,
// plain and view-independent modes walk a front with.
struct SelectiveTables {
  std::vector<NodeCriteria> criteria;  // per node
  DependencyFilter dependencies;
};

// The split records every record-coding mode sends (sender-driven packets, receiver-driven answers) and
// their code tables.
struct RecordTables {
  protocol::StoredRecords records;                           // the file's own at the served grid, or `own_records`
  EncodedRecords own_records;                                // coded when the file's records are at another grid
  std::shared_ptr<const std::vector<uint8_t>> codec_tables;  // serialized (GET /models/{m}/codec)
  std::shared_ptr<const SplitCodec> codec;                   // the tables
  std::shared_ptr<const std::vector<uint8_t>> codec_frame;   // CODEC, the tables for a sender-driven session
};

class ModelTables {
 public:
  enum class State : uint8_t { absent, queued, building, ready, failed };

  State state(ServedMode mode) const { return states_[index_of(mode)].load(std::memory_order_acquire); }
  bool ready(ServedMode mode) const { return state(mode) == State::ready; }
  // Bytes of the pieces this mode's build made (a piece two modes share is counted in the first built).
  uint64_t bytes(ServedMode mode) const { return bytes_[index_of(mode)].load(std::memory_order_relaxed); }
  uint64_t total_bytes() const;
  // Why the mode's build failed (set before its state turns failed).
  const std::string& failure(ServedMode mode) const { return failures_[index_of(mode)]; }

  // The pieces, each valid once a mode that uses it is ready.
  const SelectiveTables& selective() const { return *selective_; }
  const std::vector<uint32_t>& split_rank() const { return split_rank_; }  // per node, in split_order; leaves kNone
  // The records in `form`: the info form's serve every mode, the plain form's the receiver-driven one.
  const RecordTables& records(RecordForm form = RecordForm::info) const {
    return form == RecordForm::plain ? *plain_records_ : *records_;
  }
  const protocol::PacketTable& packets() const { return packets_; }  // sender-driven packets with refinement info
  const Dag& dag() const { return *dag_; }
  const ServedMultilevel& multilevel() const { return *multilevel_; }

 private:
  friend class TableBuilds;
  // Builds what `mode` needs that is not built yet, on the calling thread (a builder's); throws what a
  // piece's build throws. Pieces are built once each, whichever mode asks first.
  void build(const ServedModel& model, ServedMode mode);
  void set_state(ServedMode mode, State state) { states_[index_of(mode)].store(state, std::memory_order_release); }
  void build_selective(const ServedModel& model, ServedMode mode);
  void build_records(const ServedModel& model, ServedMode mode);
  void build_plain_records(const ServedModel& model, ServedMode mode);
  void count(ServedMode mode, uint64_t bytes) { bytes_[index_of(mode)] += bytes; }

  std::array<std::atomic<State>, kServedModeCount> states_{};
  std::array<std::atomic<uint64_t>, kServedModeCount> bytes_{};
  std::array<std::string, kServedModeCount> failures_;
  std::once_flag selective_once_, rank_once_, records_once_, plain_records_once_, packets_once_, dag_once_,
      multilevel_once_;
  std::unique_ptr<const SelectiveTables> selective_;
  std::vector<uint32_t> split_rank_;
  std::unique_ptr<const RecordTables> records_, plain_records_;
  protocol::PacketTable packets_;
  std::unique_ptr<const Dag> dag_;
  std::unique_ptr<const ServedMultilevel> multilevel_;
};

}  // namespace pms::server
