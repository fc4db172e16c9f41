// The catalogue a server answers from now. A reload (SIGHUP; docs/operating.md, "Signals") builds the next
// catalogue aside and swaps it in whole; each new connection and each HTTP request reads the one in place
// and keeps it (a shared_ptr) as long as it needs it, so no request ever sees a catalogue half built, and a
// model a reload dropped lives until the last session or answer that holds it ends.
#pragma once
#include <memory>
#include <mutex>
#include <utility>

#include "server/catalogue.h"

namespace pms::server {

class CatalogueSlot {
 public:
  explicit CatalogueSlot(std::shared_ptr<const Catalogue> catalogue) : current_(std::move(catalogue)) {}
  CatalogueSlot(const CatalogueSlot&) = delete;
  CatalogueSlot& operator=(const CatalogueSlot&) = delete;

  std::shared_ptr<const Catalogue> get() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return current_;
  }
  // The catalogue replaced is released outside the lock: its last holder frees it.
  void set(std::shared_ptr<const Catalogue> catalogue) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      current_.swap(catalogue);
    }
  }
  // The builders every catalogue of this slot shares (Catalogue::reload keeps them).
  TableBuilds& table_builds() const { return get()->table_builds(); }

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const Catalogue> current_;
};

}  // namespace pms::server
