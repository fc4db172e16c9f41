// How the HTTP clients find the version of a model to open and follow a model replaced under its name
// (docs/protocol.md, "Versions"): GET /models names each model's version, every other URL carries it, and
// a URL of a version the server no longer serves answers 410 with the model's entry as it is now.
// Shared with the browser build.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "client/http_transport.h"

namespace pms::client {

// pms::Error for an answer that is not the 200 `target` needed: "GET TARGET: HTTP STATUS: its body's start".
[[noreturn]] void refused(const std::string& target, const HttpAnswer& answer);
// GET /models's answer: its array of models; pms::Error naming the target for another status or body.
nlohmann::json catalogue_models(const HttpAnswer& answer);
// The entry of `model` in GET /models's answer, with a valid version; pms::Error when there is none.
nlohmann::json catalogue_entry(const HttpAnswer& answer, const std::string& model);
// The entry of `model` a 410 carries, with a valid version; pms::Error naming `target` for a 410 without
// one (or of another model).
nlohmann::json replaced_entry(const std::string& target, const HttpAnswer& answer, const std::string& model);
// The entry's version (checked by the two above).
std::string entry_version(const nlohmann::json& entry);

// The re-opens a client follows in a row (no answer of the version it opened in between), so two origins
// serving different versions of a model, or a file replaced again and again, end in an error, not a loop.
class ReopenBudget {
 public:
  static constexpr uint32_t kMostInARow = 4;
  // A 410 of `target` for `model`: the entry of the version to open (replaced_entry); pms::Error once
  // kMostInARow re-opens went by without an answer of their version.
  nlohmann::json follow(const std::string& target, const HttpAnswer& answer, const std::string& model);
  void refill() { in_a_row_ = 0; }  // an answer of the version opened came
  uint64_t total() const { return total_; }

 private:
  uint32_t in_a_row_ = 0;
  uint64_t total_ = 0;
};

}  // namespace pms::client
