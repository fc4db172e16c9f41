// `serve`'s SIGHUP (docs/operating.md, "Signals"): the models the paths given hold now, swapped in whole
// while the servers go on, and what changed logged and counted.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>

#include "server/catalogue_slot.h"
#include "server/limits.h"

namespace pms::app {

// What the reloads so far did, for the stats lines.
struct ReloadCounts {
  uint64_t reloads = 0, failed = 0;  // failed: nothing swapped, the catalogue before kept
  uint64_t added = 0, removed = 0, replaced = 0, skipped = 0;
  nlohmann::json last;  // the last reload's line (the "reloaded" event), null before any
};

// Builds the next catalogue from the one in `slot` and swaps it in; logs a line per model added, removed,
// replaced or skipped to stderr and, with `json`, prints the "reloaded" event on stdout. Never throws for
// what the files hold: a reload that cannot build a catalogue keeps the one served and says why.
void reload_models(server::CatalogueSlot& slot, const server::ServerLimits& limits, bool json, ReloadCounts& counts);

// The counters as the stats lines carry them.
nlohmann::json reload_stats(const ReloadCounts& counts);

}  // namespace pms::app
