// SIGHUP's reload (serve_reload.h): Catalogue::reload does the work aside; this file swaps, logs, counts.
#include "apps/serve_reload.h"

#include <cstdio>
#include <string>
#include <vector>

#include "server/catalogue.h"

namespace pms::app {
namespace {

void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: reload: %s\n", line.c_str()); }

void log_each(const char* what, const std::vector<std::string>& names) {
  for (const std::string& name : names) log_line(std::string(what) + " " + name);
}

nlohmann::json event_line(const server::CatalogueChanges& changes, const server::Catalogue& now) {
  return {{"event", "reloaded"},
          {"added", changes.added},
          {"removed", changes.removed},
          {"replaced", changes.replaced},
          {"kept", changes.kept},
          {"skipped", changes.skipped},
          {"models", now.models().size() + now.multilevel_models().size()}};
}

}  // namespace

void reload_models(server::CatalogueSlot& slot, const server::ServerLimits& limits, bool json, ReloadCounts& counts) {
  ++counts.reloads;
  server::CatalogueChanges changes;
  std::shared_ptr<const server::Catalogue> next;
  try {
    next = server::Catalogue::reload(*slot.get(), limits, changes);
  } catch (const std::exception& e) {
    ++counts.failed;
    log_each("skipped", changes.skipped);
    log_line(std::string("failed, the models served are kept: ") + e.what());
    counts.last = {{"event", "reload_failed"}, {"error", e.what()}, {"skipped", changes.skipped}};
    if (json) std::printf("%s\n", counts.last.dump().c_str());
    std::fflush(stdout);
    return;
  }
  slot.set(next);
  counts.added += changes.added.size();
  counts.removed += changes.removed.size();
  counts.replaced += changes.replaced.size();
  counts.skipped += changes.skipped.size();
  log_each("added", changes.added);
  log_each("removed (dropped when its last session ends)", changes.removed);
  log_each("replaced (a new version)", changes.replaced);
  log_each("skipped", changes.skipped);
  log_line(std::to_string(next->models().size() + next->multilevel_models().size()) + " models served, " +
           std::to_string(changes.kept.size()) + " unchanged");
  counts.last = event_line(changes, *next);
  if (json) std::printf("%s\n", counts.last.dump().c_str());
  std::fflush(stdout);
}

nlohmann::json reload_stats(const ReloadCounts& counts) {
  return {{"reloads", counts.reloads},           {"reloads_failed", counts.failed},
          {"models_added", counts.added},       {"models_removed", counts.removed},
          {"models_replaced", counts.replaced}, {"files_skipped", counts.skipped}};
}

}  // namespace pms::app
