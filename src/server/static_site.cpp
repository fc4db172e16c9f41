// The page's files: a URL to a file under the root (site_path.h), its bytes from a small cache checked
// against the file's identity on disk at each request, and a 200 or 304 with a strong ETag.
#define XXH_INLINE_ALL
#include <xxhash.h>
#include "server/static_site.h"

#include <sys/stat.h>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "server/http_answers.h"
#include "server/site_path.h"

namespace pms::server {
namespace {

constexpr const char* kNotBuilt =
    "the page is not built: build the web part (scripts/setup.sh, or cmake with -DPMSTREAM_WEB=ON and the "
    "target web), or point serve --web-root at a directory holding index.html";

std::string canonical(const std::string& path) {
  char resolved[PATH_MAX];
  return realpath(path.c_str(), resolved) ? std::string(resolved) : std::string();
}

bool inside(const std::string& path, const std::string& root) {
  return path.size() > root.size() && path.compare(0, root.size(), root) == 0 && path[root.size()] == '/';
}

int64_t modified_ns(const struct stat& s) { return int64_t(s.st_mtim.tv_sec) * 1000000000 + s.st_mtim.tv_nsec; }

bool same_file(const struct stat& s, uint64_t device, uint64_t inode, uint64_t size, int64_t modified) {
  return uint64_t(s.st_dev) == device && uint64_t(s.st_ino) == inode && uint64_t(s.st_size) == size &&
         modified_ns(s) == modified;
}

}  // namespace

const char* site_content_type(std::string_view path) {
  static constexpr std::pair<std::string_view, const char*> kTypes[] = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".wasm", "application/wasm"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".png", "image/png"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"},
  };
  for (const auto& [extension, type] : kTypes)
    if (path.ends_with(extension)) return type;
  return "application/octet-stream";
}

StaticSite::StaticSite(std::string root, const SiteLimits& limits) : limits_(limits) {
  struct stat s{};
  if (!root.empty() && stat(root.c_str(), &s) == 0 && S_ISDIR(s.st_mode)) {
    root_ = canonical(root);
    present_ = !root_.empty();
  }
  if (!present_ && !root.empty()) {  // said once, here: the 404s say it to the browser
    std::fprintf(stderr, "pmstream serve: http: no page at '%s': %s\n", root.c_str(), kNotBuilt);
    root_ = root;
  }
}

HttpAnswer StaticSite::answer(const HttpRequest& request) {
  if (request.method != "GET" && request.method != "HEAD") return method_not_allowed("GET, HEAD");
  if (!present_) return error_answer(404, kNotBuilt);
  const std::optional<std::string> relative = site_path(request.target);
  if (!relative) return error_answer(404, "no such file");
  HttpAnswer refusal;
  const std::shared_ptr<const File> found = file(*relative, refusal);
  if (!found) return refusal;
  HttpAnswer answer = fresh(request, found->etag, site_content_type(*relative));
  answer.caching = Caching::revalidate;
  if (answer.status == 200) answer.shared = found->bytes;
  return answer;
}

std::shared_ptr<const StaticSite::File> StaticSite::file(const std::string& relative, HttpAnswer& refusal) {
  refusal = error_answer(404, "no such file");
  // Resolved each time: a symlink changed on disk is followed where it points now.
  const std::string resolved = canonical(root_ + '/' + relative);
  if (resolved.empty() || !inside(resolved, root_)) return nullptr;
  struct stat s{};
  if (stat(resolved.c_str(), &s) != 0 || !S_ISREG(s.st_mode)) return nullptr;  // no directory listing
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = files_.find(resolved);
    if (it != files_.end() && same_file(s, it->second->device, it->second->inode, it->second->size,
                                        it->second->modified_ns))
      return it->second;
  }
  return read_file(resolved, refusal);
}

std::shared_ptr<const StaticSite::File> StaticSite::read_file(const std::string& resolved, HttpAnswer& refusal) {
  auto file = std::make_shared<File>();
  struct stat s{};
  std::ifstream in(resolved, std::ios::binary);
  if (!in || stat(resolved.c_str(), &s) != 0) return nullptr;
  if (uint64_t(s.st_size) > limits_.max_file_bytes) {
    refusal = error_answer(403, "the file is over the server's size cap");
    return nullptr;
  }
  auto bytes = std::make_shared<std::vector<uint8_t>>(size_t(s.st_size));
  in.read(reinterpret_cast<char*>(bytes->data()), std::streamsize(bytes->size()));
  if (!in || in.peek() != std::ifstream::traits_type::eof()) {  // changed while read: the next request reads it again
    refusal = error_answer(503, "the file changed while it was read");
    return nullptr;
  }
  file->device = uint64_t(s.st_dev);
  file->inode = uint64_t(s.st_ino);
  file->size = uint64_t(s.st_size);
  file->modified_ns = modified_ns(s);
  file->etag = etag_text(XXH64(bytes->data(), bytes->size(), 0));
  file->bytes = std::move(bytes);
  std::lock_guard<std::mutex> lock(mutex_);
  // The tree is small; a cache past its cap means files keep changing: start over rather than track ages.
  if (cached_bytes_ + file->size > limits_.max_cached_bytes) {
    files_.clear();
    cached_bytes_ = 0;
  }
  if (auto& slot = files_[resolved]) cached_bytes_ -= std::min(cached_bytes_, slot->size);
  files_[resolved] = file;
  cached_bytes_ += file->size;
  return file;
}

}  // namespace pms::server
