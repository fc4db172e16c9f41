// The models a server offers: opened once, memory-mapped, shared read-only by every session; each mode's
// tables built by the catalogue's TableBuilds.
#define XXH_INLINE_ALL
#include <xxhash.h>
#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>

#include "common/error.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/url_segment.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "spm/pms_file.h"

namespace pms::server {
namespace {

namespace fs = std::filesystem;

// The model files `paths` name, in order (a directory's sorted); a path that is neither a file nor a
// listable directory goes to `skip` with why.
std::vector<std::string> model_files(const std::vector<std::string>& paths,
                                     const std::function<void(const std::string&, const std::string&)>& skip) {
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : fs::directory_iterator(path, ec))
        if (entry.is_regular_file() && (entry.path().extension() == ".pms" || entry.path().extension() == ".pml"))
          found.push_back(entry.path().string());
      if (ec) {
        skip(path, "cannot list directory: " + ec.message());
        continue;
      }
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else if (fs::exists(path, ec)) {
      files.push_back(path);
    } else {
      skip(path, "no such file or directory");
    }
  }
  return files;
}

std::shared_ptr<ServedModel> open_model(const std::string& path, std::unique_ptr<PmsFile> file,
                                        uint32_t position_bits) {
  auto model = std::make_shared<ServedModel>();
  model->path = path;
  model->name = fs::path(path).stem().string();
  model->file = std::move(file);
  const ModelData& data = model->file->model();
  model->info = protocol::model_info(data, model->name);
  const protocol::Base base = protocol::make_base(data, model->name, position_bits);
  model->context = protocol::stream_context(base);
  model->version = content_version(model->file->content_checksum(), model->context.grid.bits);
  model->base_frame = std::make_shared<const std::vector<uint8_t>>(protocol::encode(base));
  model->tables = std::make_unique<ModelTables>();
  return model;
}

// previous's model of `path` when the file there still has its content: its mapping and tables carry over.
std::shared_ptr<ServedModel> unchanged_model(const Catalogue& previous, const std::string& path,
                                             const PmsFile& file) {
  for (const auto& model : previous.models())
    if (model->path == path && model->file->content_checksum() == file.content_checksum()) return model;
  return nullptr;
}

// The version each model name has in `catalogue`, progressive and multilevel alike.
std::map<std::string, std::string> versions(const Catalogue& catalogue) {
  std::map<std::string, std::string> out;
  for (const auto& model : catalogue.models()) out[model->name] = model->version;
  for (const auto& model : catalogue.multilevel_models()) out[model->name] = model->version;
  return out;
}

void diff(const Catalogue& before, const Catalogue& after, CatalogueChanges& changes) {
  const std::map<std::string, std::string> old = versions(before), now = versions(after);
  for (const auto& [name, version] : now) {
    const auto it = old.find(name);
    if (it == old.end()) changes.added.push_back(name);
    else if (it->second != version) changes.replaced.push_back(name);
    else changes.kept.push_back(name);
  }
  for (const auto& [name, version] : old)
    if (!now.contains(name)) changes.removed.push_back(name);
}

std::string frame_limit_failure(const ServedModel& model, const ServerLimits& limits) {
  const uint64_t payload = model.base_frame->size() - protocol::kFrameHeaderBytes;
  if (payload <= limits.max_server_message) return {};
  return "its BASE message is " + std::to_string(payload) + " bytes, over --max-server-message " +
         std::to_string(limits.max_server_message) + " (raise it, or serve the model with fewer base vertices)";
}

}  // namespace

std::string content_version(uint64_t content_checksum, uint32_t grid_bits) {
  const uint64_t parts[3] = {content_checksum, grid_bits, ServedModel::records_format};
  return protocol::model_version_text(XXH64(parts, sizeof parts, 0));
}

void Catalogue::finish() {
  protocol::Catalogue message;
  for (const auto& model : models_) message.models.push_back(model->info);
  catalogue_frame_ = std::make_shared<const std::vector<uint8_t>>(protocol::encode(message));
}

std::shared_ptr<const Catalogue> Catalogue::open(const std::vector<std::string>& paths, uint32_t position_bits,
                                                 const TableOptions& tables) {
  auto catalogue = std::make_shared<Catalogue>();
  catalogue->paths_ = paths;
  catalogue->position_bits_ = position_bits;
  catalogue->preload_ = tables.preload;
  catalogue->builds_ = std::make_shared<TableBuilds>(tables.max_builds);
  const auto check_unique = [&](const std::string& file, const std::string& name) {
    if (catalogue->find(name) || catalogue->find_multilevel(name))
      fail(file, "a model named '" + name + "' is already served");
  };
  const auto missing = [](const std::string& path, const std::string& why) { fail(path, why); };
  for (const std::string& file : model_files(paths, missing)) {
    if (fs::path(file).extension() == ".pml") {
      auto model = open_multilevel(file);
      check_unique(file, model->name);
      catalogue->multilevel_.push_back(std::move(model));
      continue;
    }
    auto model = open_model(file, PmsFile::open(file), position_bits);
    check_unique(file, model->name);
    catalogue->models_.push_back(std::move(model));
  }
  if (catalogue->models_.empty() && catalogue->multilevel_.empty())
    fail("serve", "no .pms or .pml models found in the paths given");
  catalogue->finish();
  std::vector<const ServedModel*> models;
  for (const auto& model : catalogue->models_) models.push_back(model.get());
  catalogue->builds_->build_all(models, tables.preload);
  return catalogue;
}

std::shared_ptr<const Catalogue> Catalogue::reload(const Catalogue& previous, const ServerLimits& limits,
                                                   CatalogueChanges& changes) {
  auto catalogue = std::make_shared<Catalogue>();
  catalogue->paths_ = previous.paths_;
  catalogue->position_bits_ = previous.position_bits_;
  catalogue->preload_ = previous.preload_;
  catalogue->builds_ = previous.builds_;
  const auto skip = [&](const std::string& path, const std::string& why) { changes.skipped.push_back(path + ": " + why); };
  std::vector<const ServedModel*> opened;  // new or changed: their preloaded tables to queue
  for (const std::string& file : model_files(previous.paths_, skip)) {
    try {
      const std::string name = fs::path(file).stem().string();
      if (catalogue->find(name) || catalogue->find_multilevel(name)) {
        skip(file, "a model named '" + name + "' is already served");
        continue;
      }
      if (fs::path(file).extension() == ".pml") {  // read whole, nothing built later: opened anew
        catalogue->multilevel_.push_back(open_multilevel(file));
        continue;
      }
      std::unique_ptr<PmsFile> mapped = PmsFile::open(file);
      std::shared_ptr<ServedModel> model = unchanged_model(previous, file, *mapped);
      if (!model) {
        model = open_model(file, std::move(mapped), catalogue->position_bits_);
        if (const std::string why = frame_limit_failure(*model, limits); !why.empty()) {
          skip(file, why);
          continue;
        }
        opened.push_back(model.get());
      }
      catalogue->models_.push_back(std::move(model));
    } catch (const std::exception& e) {  // pms::Error names the file
      changes.skipped.push_back(e.what());
    }
  }
  if (catalogue->models_.empty() && catalogue->multilevel_.empty())
    fail("reload", "no .pms or .pml model could be opened in the paths given; the models served are kept");
  catalogue->finish();
  catalogue->check_limits(limits);
  diff(previous, *catalogue, changes);
  catalogue->builds_->queue_all(opened, catalogue->preload_);
  return catalogue;
}

void Catalogue::check_limits(const ServerLimits& limits) const {
  const auto payload = [](const std::vector<uint8_t>& frame) { return frame.size() - protocol::kFrameHeaderBytes; };
  const std::string limit = " bytes, over --max-server-message " + std::to_string(limits.max_server_message) +
                            " (raise it, or serve the model with fewer base vertices)";
  for (const auto& model : models_)
    if (const std::string why = frame_limit_failure(*model, limits); !why.empty()) fail(model->path, why);
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
