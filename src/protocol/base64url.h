// base64url without padding (RFC 4648 §5): how a request code travels in a URL path, so the GET form of a
// request is one fixed string per id set and caches can share it. Shared with the browser build.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pms::protocol {

std::string base64url_encode(std::span<const uint8_t> bytes);

// The bytes, or nothing for text that is not the canonical encoding of some bytes: a character outside
// the alphabet, padding ('='), a length of 1 mod 4, or non-zero bits after the last byte.
std::optional<std::vector<uint8_t>> base64url_decode(std::string_view text);

}  // namespace pms::protocol
