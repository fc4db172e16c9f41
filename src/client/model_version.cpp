// GET /models and 410 answers read for a model's version (model_version.h).
#include "client/model_version.h"

#include <algorithm>

#include "common/error.h"
#include "protocol/url_segment.h"

namespace pms::client {
namespace {

std::string text_of(const HttpAnswer& answer) {
  std::string text(answer.body.begin(), answer.body.begin() + std::min<size_t>(answer.body.size(), 200));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return text;
}

bool is_entry_of(const nlohmann::json& entry, const std::string& model) {
  if (!entry.is_object() || entry.value("name", "") != model) return false;
  const auto version = entry.find("version");
  return version != entry.end() && version->is_string() && protocol::is_model_version(version->get<std::string>());
}

}  // namespace

void refused(const std::string& target, const HttpAnswer& answer) {
  fail("GET " + target, "HTTP " + std::to_string(answer.status) + ": " + text_of(answer));
}

nlohmann::json catalogue_models(const HttpAnswer& answer) {
  const std::string where = "GET /models";
  if (answer.status != 200) refused("/models", answer);
  nlohmann::json json = nlohmann::json::parse(answer.body.begin(), answer.body.end(), nullptr, false);
  if (json.is_discarded() || !json.is_object() || !json.contains("models") || !json["models"].is_array())
    fail(where, "not the catalogue's JSON");
  return std::move(json["models"]);
}

nlohmann::json catalogue_entry(const HttpAnswer& answer, const std::string& model) {
  for (nlohmann::json& entry : catalogue_models(answer))
    if (is_entry_of(entry, model)) return std::move(entry);
  fail("GET /models", "no model named '" + model + "' (with a version) in the catalogue");
}

nlohmann::json replaced_entry(const std::string& target, const HttpAnswer& answer, const std::string& model) {
  const nlohmann::json json = nlohmann::json::parse(answer.body.begin(), answer.body.end(), nullptr, false);
  if (json.is_object() && json.contains("model") && is_entry_of(json["model"], model)) return json["model"];
  fail("GET " + target, "HTTP 410 without the entry of model '" + model + "': " + text_of(answer));
}

std::string entry_version(const nlohmann::json& entry) { return entry["version"].get<std::string>(); }

nlohmann::json ReopenBudget::follow(const std::string& target, const HttpAnswer& answer, const std::string& model) {
  nlohmann::json entry = replaced_entry(target, answer, model);
  if (++in_a_row_ > kMostInARow)
    fail("open", "model '" + model + "' changed version " + std::to_string(kMostInARow) +
                     " times in a row with no answer of the version opened (origins serving different files?)");
  ++total_;
  return entry;
}

}  // namespace pms::client
