// The models a server offers: opened once, memory-mapped, shared read-only by every session; each mode's
// tables built by the catalogue's TableBuilds.
#include <algorithm>
#include <filesystem>

#include "common/error.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "spm/pms_file.h"

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
  model->tables = std::make_unique<ModelTables>();
  return model;
}

}  // namespace

std::shared_ptr<const Catalogue> Catalogue::open(const std::vector<std::string>& paths, uint32_t position_bits,
                                                 const TableOptions& tables) {
  auto catalogue = std::make_shared<Catalogue>();
  catalogue->builds_ = std::make_unique<TableBuilds>(tables.max_builds);
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
  std::vector<const ServedModel*> models;
  for (const auto& model : catalogue->models_) models.push_back(model.get());
  catalogue->builds_->build_all(models, tables.preload);
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

uint64_t Catalogue::table_bytes() const {
  uint64_t total = 0;
  for (const auto& model : models_) total += model->tables->total_bytes();
  return total;
}

uint64_t Catalogue::mapped_bytes() const {
  uint64_t total = 0;
  for (const auto& model : models_) total += model->file->file_size();
  return total;
}

}  // namespace pms::server
