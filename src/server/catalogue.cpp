// The models a server offers: opened once, memory-mapped, shared read-only by every session.
#include <algorithm>
#include <filesystem>

#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/packet_table.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/refine_info.h"
#include "spm/split_codec.h"
#include "spm/vertex_id.h"

namespace pms::server {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> model_files(const std::vector<std::string>& paths) {
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : fs::directory_iterator(path, ec))
        if (entry.is_regular_file() && (entry.path().extension() == ".pms" || entry.path().extension() == ".pml"))
          found.push_back(entry.path().string());
      if (ec) fail(path, "cannot list directory: " + ec.message());
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else if (fs::exists(path, ec)) {
      files.push_back(path);
    } else {
      fail(path, "no such file or directory");
    }
  }
  return files;
}

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

// The .pms holds records at the grid it was built for; a server started with other position bits codes
// its own once.
void attach_records(ServedModel& model) {
  const PmsFile& file = *model.file;
  const uint32_t bits = model.context.grid.bits;
  const SplitCodec* codec = &file.split_codec();
  if (!file.split_offsets().empty() && codec->position_bits() == bits) {
    model.records = {file.split_records(), file.split_offsets()};
  } else {
    model.own_records = encode_records(file.model(), bits);
    model.records = {model.own_records.records, model.own_records.offsets};
  }
  if (!model.own_records.tables.empty()) {
    model.codec_tables = std::make_shared<const std::vector<uint8_t>>(model.own_records.tables);
  } else {
    BitWriter w;
    codec->serialize(w);
    model.codec_tables = std::make_shared<const std::vector<uint8_t>>(w.bytes());
  }
  BitReader tables(*model.codec_tables, "split tables");
  model.codec = std::make_shared<const SplitCodec>(SplitCodec::deserialize(tables));
  model.codec_frame =
      std::make_shared<const std::vector<uint8_t>>(protocol::encode(protocol::Codec{*model.codec_tables, {}}));
}

std::unique_ptr<ServedModel> open_model(const std::string& path, uint32_t position_bits) {
  auto model = std::make_unique<ServedModel>();
  model->path = path;
  model->name = fs::path(path).stem().string();
  model->file = PmsFile::open(path);
  const ModelData& data = model->file->model();
  model->info = protocol::model_info(data, model->name);
  const protocol::Base base = protocol::make_base(data, model->name, position_bits);
  model->context = protocol::stream_context(base);
  model->base_frame = std::make_shared<const std::vector<uint8_t>>(protocol::encode(base));
  model->criteria = decode_criteria(data, model->context.grid);
  model->split_rank.assign(data.node_count(), kNone);
  for (uint32_t i = 0; i < data.split_order.size(); ++i) model->split_rank[data.split_order[i]] = i;
  model->dependencies = DependencyFilter(data);
  model->dag = std::make_unique<const Dag>(data, snapped_positions(data, model->context.grid));
  attach_records(*model);
  // The sender-driven packets: v_s's id and its stored record (docs/protocol.md, "VSPLITS").
  protocol::StreamContext sender = model->context;
  sender.has_refinement = true;
  sender.records = model->codec;
  model->packets = protocol::PacketTable(data, sender, model->records);
  return model;
}

}  // namespace

std::shared_ptr<const Catalogue> Catalogue::open(const std::vector<std::string>& paths, uint32_t position_bits) {
  auto catalogue = std::make_shared<Catalogue>();
  const auto check_unique = [&](const std::string& file, const std::string& name) {
    if (catalogue->find(name) || catalogue->find_multilevel(name))
      fail(file, "a model named '" + name + "' is already served");
  };
  for (const std::string& file : model_files(paths)) {
    if (fs::path(file).extension() == ".pml") {
      auto model = open_multilevel(file);
      check_unique(file, model->name);
      catalogue->multilevel_.push_back(std::move(model));
      continue;
    }
    auto model = open_model(file, position_bits);
    check_unique(file, model->name);
    catalogue->models_.push_back(std::move(model));
  }
  if (catalogue->models_.empty() && catalogue->multilevel_.empty())
    fail("serve", "no .pms or .pml models found in the paths given");
  protocol::Catalogue message;
  for (const auto& model : catalogue->models_) message.models.push_back(model->info);
  catalogue->catalogue_frame_ = std::make_shared<const std::vector<uint8_t>>(protocol::encode(message));
  return catalogue;
}

void Catalogue::check_limits(const ServerLimits& limits) const {
  const auto payload = [](const std::vector<uint8_t>& frame) { return frame.size() - protocol::kFrameHeaderBytes; };
  const std::string limit = " bytes, over --max-server-message " + std::to_string(limits.max_server_message) +
                            " (raise it, or serve the model with fewer base vertices)";
  for (const auto& model : models_)
    if (payload(*model->base_frame) > limits.max_server_message)
      fail(model->path, "its BASE message is " + std::to_string(payload(*model->base_frame)) + limit);
  if (payload(*catalogue_frame_) > limits.max_server_message)
    fail("serve", "the CATALOGUE of " + std::to_string(models_.size()) + " models is " +
                      std::to_string(payload(*catalogue_frame_)) + limit);
  // A vsplit packet is under 1024 bits (PacketTable), a VSPLITS header 9 bytes.
  const uint64_t batch = uint64_t(limits.batch_splits) * 128 + 16;
  if (batch > limits.max_server_message)
    fail("serve", "--batch " + std::to_string(limits.batch_splits) + ": a VSPLITS message may take " +
                      std::to_string(batch) + limit);
  if (limits.batch_splits == 0 || limits.slice_work == 0) fail("serve", "--batch and the slice work must be >= 1");
}

const ServedModel* Catalogue::find(const std::string& name) const {
  for (const auto& model : models_)
    if (model->name == name) return model.get();
  return nullptr;
}

const ServedMultilevel* Catalogue::find_multilevel(const std::string& name) const {
  for (const auto& model : multilevel_)
    if (model->name == name) return model.get();
  return nullptr;
}

uint64_t Catalogue::mapped_bytes() const {
  uint64_t total = 0;
  for (const auto& model : models_) total += model->file->file_size();
  return total;
}

}  // namespace pms::server
