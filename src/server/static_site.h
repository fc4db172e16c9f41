// The page's files (serve --web-root): GET and HEAD of the files under one directory, each read once and
// kept while it is unchanged on disk (the tree is a few files), with a strong ETag from its content and
// Cache-Control: no-cache, so a browser revalidates on every load (the names are not content-hashed) and
// gets a 304 while nothing changed. docs/operating.md, "The page", lists its bounds.
#pragma once
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "server/http_routes.h"

namespace pms::server {

struct SiteLimits {
  uint64_t max_file_bytes = 64u << 20;    // a larger file is refused (the WASM core is the largest)
  uint64_t max_cached_bytes = 256u << 20;  // all the files kept: past it, the cache starts over
};

// Thread-safe: the HTTP server's threads share one.
class StaticSite {
 public:
  // `root` empty or missing: every page route answers 404 saying how to build the page.
  explicit StaticSite(std::string root, const SiteLimits& limits = {});

  bool present() const { return present_; }
  const std::string& root() const { return root_; }
  // The answer to a request for a page route (anything outside the API's /models).
  HttpAnswer answer(const HttpRequest& request);

 private:
  struct File {
    uint64_t device = 0, inode = 0, size = 0;
    int64_t modified_ns = 0;
    std::shared_ptr<const std::vector<uint8_t>> bytes;
    std::string etag;
  };
  // The file at `relative` as it is on disk now, from the cache when unchanged; nothing when it is not a
  // regular file inside the root (a symlink may point anywhere inside it, never outside).
  std::shared_ptr<const File> file(const std::string& relative, HttpAnswer& refusal);
  std::shared_ptr<const File> read_file(const std::string& resolved, HttpAnswer& refusal);

  std::string root_;           // canonical (realpath), with no trailing '/'
  bool present_ = false;
  SiteLimits limits_;
  std::mutex mutex_;
  std::unordered_map<std::string, std::shared_ptr<const File>> files_;  // by canonical path
  uint64_t cached_bytes_ = 0;
};

// The Content-Type of a page file by its extension; application/octet-stream for others.
const char* site_content_type(std::string_view path);

}  // namespace pms::server
