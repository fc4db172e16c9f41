// A model's name as one segment of a URL path (RFC 3986 §3.3), and the path of its resources. Names come
// from file names, so they may hold spaces, '%' or UTF-8. Shared with the browser build.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace pms::protocol {

// Every byte outside the unreserved set (ALPHA, DIGIT, "-", ".", "_", "~") as %XX in upper-case hex: one
// name has one URL, so clients behind a cache share its entries.
std::string url_segment_encode(std::string_view name);

// The name a segment stands for, decoding %XX in either case and taking RFC 3986's other path characters
// (sub-delims, ':', '@') as they are, as a hand-typed URL may hold them; nothing for a '%' without two hex
// digits, a byte no path segment may hold raw, or a decoded '/' or NUL (no name holds them).
std::optional<std::string> url_segment_decode(std::string_view segment);

// `path` in RFC 3986's normal form: escapes of unreserved characters decoded (§6.2.2.2), the hex of the
// others in upper case (§6.2.2.1), so two spellings of one path compare equal; nothing for a '%' without
// two hex digits or a byte no path may hold raw.
std::optional<std::string> url_path_normalize(std::string_view path);

// A port as an address's authority spells it: decimal, 1 … 65535, nothing else; nothing otherwise.
std::optional<uint16_t> parse_port(std::string_view digits);

// A model's content version as URLs carry it (docs/protocol.md, "Versions"): 16 lower-case hex digits, one
// spelling per version, so one URL per resource.
constexpr size_t kModelVersionChars = 16;
bool is_model_version(std::string_view text);
// The version spelling of a 64-bit hash of what a version's bytes depend on.
std::string model_version_text(uint64_t hash);

// "/models/", the encoded name and the version: where every resource of that version of the model starts.
std::string model_path(std::string_view name, std::string_view version);

}  // namespace pms::protocol
