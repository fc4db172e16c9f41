// Which file under the page's root a URL names (serve --web-root): the one place that decides whether a
// request may leave the root, so every spelling of a way out is refused here, before the file system is
// asked anything (docs/operating.md, "The page").
#pragma once
#include <optional>
#include <string>
#include <string_view>

namespace pms::server {

// The path relative to the root that `target` names ("/" is "index.html"; the query is ignored), or
// nothing when it names no file a client may have: a segment that decodes to "", ".", ".." or begins with
// '.' (hidden files, and every dot-segment spelling: "..", "%2e%2e", ".%2E"), an escaped '/' or '\', a raw
// '\', a NUL, a '%' without two hex digits, or a directory (a trailing '/': no listing).
std::optional<std::string> site_path(std::string_view target);

}  // namespace pms::server
