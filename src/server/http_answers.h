// What every route file shares (http_routes.cpp, multilevel_routes.cpp): the answer for a resource with
// its ETag, an ETag's text, the one spelling of a number in a URL, and a 405.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

#include "server/http_routes.h"

namespace pms::server {

// A 200 for `etag` (cacheable, immutable), or a 304 when the client holds it already; no body yet.
HttpAnswer fresh(const HttpRequest& request, const std::string& etag, const char* content_type);
// A strong ETag for a 64-bit hash of what the resource's bytes depend on: quoted base64url (RFC 4648 §5),
// 13 bytes where hex takes 18, sent with every answer.
std::string etag_text(uint64_t hash);
// Decimal without sign or leading zeros: one spelling per number, so one URL per resource.
bool parse_decimal(std::string_view text, uint64_t& value);
HttpAnswer method_not_allowed(const char* allow);

}  // namespace pms::server
