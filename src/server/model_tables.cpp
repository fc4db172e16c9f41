// A served model's tables, each built once on a builder's thread (model_tables.h).
#include "server/model_tables.h"

#include "common/bit_stream.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "server/catalogue.h"
#include "server/derived_multilevel.h"
#include "spm/refine_info.h"

namespace pms::server {
namespace {

// qrefine's inputs per node on the positions the clients will hold (snapped to the wire grid).
std::vector<NodeCriteria> decode_criteria(const ModelData& model, const protocol::PositionGrid& grid) {
  std::vector<NodeCriteria> criteria(model.node_count());
  for (size_t n = 0; n < criteria.size(); ++n) {
    float p[3];
    protocol::snap_position(grid, &model.position[3 * n], p);
    criteria[n] = node_criteria(p, dequantize_refine(model.refine[n], model.scale));
  }
  return criteria;
}

// Every node's position as the clients hold it, for the DAG's ERROR-EVALUATE.
std::vector<float> snapped_positions(const ModelData& model, const protocol::PositionGrid& grid) {
  std::vector<float> positions(3 * size_t(model.node_count()));
  for (size_t n = 0; n < model.node_count(); ++n)
    protocol::snap_position(grid, &model.position[3 * n], &positions[3 * n]);
  return positions;
}

// The serialized tables `tables`, decoded once, and the CODEC frame that carries them.
void hold_tables(RecordTables& out, std::vector<uint8_t> tables) {
  out.codec_tables = std::make_shared<const std::vector<uint8_t>>(std::move(tables));
  BitReader reader(*out.codec_tables, "split tables");
  out.codec = std::make_shared<const SplitCodec>(SplitCodec::deserialize(reader));
  out.codec_frame =
      std::make_shared<const std::vector<uint8_t>>(protocol::encode(protocol::Codec{*out.codec_tables, {}}));
}

// The .pms holds records at the grid it was built for; a server started with other position bits codes
// its own once.
std::unique_ptr<RecordTables> record_tables(const ServedModel& served) {
  auto out = std::make_unique<RecordTables>();
  const PmsFile& file = *served.file;
  const uint32_t bits = served.context.grid.bits;
  const SplitCodec& codec = file.split_codec();
  if (!file.split_offsets().empty() && codec.position_bits() == bits) {
    out->records = {file.split_records(), file.split_offsets()};
    BitWriter w;
    codec.serialize(w);
    hold_tables(*out, w.bytes());
  } else {
    out->own_records = encode_records(file.model(), bits);
    out->records = {out->own_records.records, out->own_records.offsets};
    hold_tables(*out, out->own_records.tables);
  }
  return out;
}

// The plain form (docs/protocol.md, "The plain form") is derived from the same model at load: the file
// stores the info form only, so both forms come from one .pms.
std::unique_ptr<RecordTables> plain_record_tables(const ServedModel& served) {
  auto out = std::make_unique<RecordTables>();
  out->own_records = encode_records(served.model(), served.context.grid.bits, RecordForm::plain);
  out->records = {out->own_records.records, out->own_records.offsets, RecordForm::plain};
  hold_tables(*out, out->own_records.tables);
  return out;
}

uint64_t record_bytes(const RecordTables& r) {
  const EncodedRecords& own = r.own_records;
  return own.tables.capacity() + own.records.capacity() + own.offsets.capacity() * sizeof(uint64_t) +
         r.codec_tables->size() + r.codec_frame->size();
}

}  // namespace

uint64_t ModelTables::total_bytes() const {
  uint64_t total = 0;
  for (const auto& bytes : bytes_) total += bytes.load(std::memory_order_relaxed);
  return total;
}

void ModelTables::build_selective(const ServedModel& served, ServedMode mode) {
  std::call_once(selective_once_, [&] {
    auto tables = std::make_unique<SelectiveTables>();
    tables->criteria = decode_criteria(served.model(), served.context.grid);
    tables->dependencies = DependencyFilter(served.model());
    count(mode, tables->criteria.capacity() * sizeof(NodeCriteria) + tables->dependencies.memory_bytes());
    selective_ = std::move(tables);
  });
}

void ModelTables::build_records(const ServedModel& served, ServedMode mode) {
  std::call_once(records_once_, [&] {
    records_ = record_tables(served);
    count(mode, record_bytes(*records_));
  });
}

void ModelTables::build_plain_records(const ServedModel& served, ServedMode mode) {
  std::call_once(plain_records_once_, [&] {
    plain_records_ = plain_record_tables(served);
    count(mode, record_bytes(*plain_records_));
  });
}

void ModelTables::build(const ServedModel& served, ServedMode mode) {
  const ModelData& data = served.model();
  switch (mode) {
    case ServedMode::sender:
      build_selective(served, mode);
      build_records(served, mode);
      // The sender-driven packets: v_s's id and its stored record (docs/protocol.md, "VSPLITS").
      std::call_once(packets_once_, [&] {
        protocol::StreamContext sender = served.context;
        sender.has_refinement = true;
        sender.records = records_->codec;
        packets_ = protocol::PacketTable(data, sender, records_->records);
        count(mode, packets_.memory_bytes());
      });
      return;
    case ServedMode::sender_plain:
      return build_selective(served, mode);
    case ServedMode::view_independent:
      build_selective(served, mode);
      std::call_once(rank_once_, [&] {
        split_rank_.assign(data.node_count(), kNone);
        for (uint32_t i = 0; i < data.split_order.size(); ++i) split_rank_[data.split_order[i]] = i;
        count(mode, split_rank_.capacity() * sizeof(uint32_t));
      });
      return;
    case ServedMode::dag:
      std::call_once(dag_once_, [&] {
        dag_ = std::make_unique<const Dag>(data, snapped_positions(data, served.context.grid));
        count(mode, dag_->memory_bytes());
      });
      return;
    case ServedMode::receiver:
      build_records(served, mode);
      return build_plain_records(served, mode);
    case ServedMode::multilevel:
      std::call_once(multilevel_once_, [&] {
        multilevel_ = derive_multilevel(served.name, served.path, served.version, data);
        count(mode, multilevel_->memory_bytes());
      });
      return;
  }
}

}  // namespace pms::server
