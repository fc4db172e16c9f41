// A URL path to a file under the page's root, refusing whatever could name something outside it.
#include "server/site_path.h"

#include "protocol/url_segment.h"

namespace pms::server {
namespace {

// Deeper trees than the page's are not served: a bound on the work one URL asks for.
constexpr size_t kMaxSegments = 16;

bool segment_allowed(std::string_view name) {
  if (name.empty() || name.front() == '.') return false;  // "", ".", "..", ".git", ".%2e"
  return name.find('\\') == std::string_view::npos;       // another spelling of '/' on some systems
}

}  // namespace

std::optional<std::string> site_path(std::string_view target) {
  target = target.substr(0, target.find('?'));
  if (target.empty() || target.front() != '/') return std::nullopt;
  if (target == "/") return std::string("index.html");
  std::string path;
  size_t segments = 0;
  while (!target.empty()) {
    target.remove_prefix(1);  // the '/'
    const size_t end = std::min(target.find('/'), target.size());
    // Decoding refuses a bad '%', a byte no path holds raw, and an escaped '/' or NUL.
    const std::optional<std::string> name = protocol::url_segment_decode(target.substr(0, end));
    if (!name || !segment_allowed(*name) || ++segments > kMaxSegments) return std::nullopt;
    if (!path.empty()) path += '/';
    path += *name;
    target.remove_prefix(end);
  }
  return path;
}

}  // namespace pms::server
