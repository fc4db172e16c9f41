#include "protocol/url_segment.h"

namespace pms::protocol {
namespace {

bool unreserved(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '.' ||
         c == '_' || c == '~';
}

bool raw_path_char(unsigned char c) {
  return unreserved(c) || std::string_view("!$&'()*+,;=:@").find(char(c)) != std::string_view::npos;
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// The byte "%XX" at `at` stands for; -1 when two hex digits do not follow.
int escaped_byte(std::string_view text, size_t at) {
  if (at + 2 >= text.size()) return -1;
  const int high = hex_value(text[at + 1]), low = hex_value(text[at + 2]);
  return high < 0 || low < 0 ? -1 : high << 4 | low;
}

void append_escaped(std::string& out, unsigned char c) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  out += '%';
  out += kHex[c >> 4];
  out += kHex[c & 15];
}

// Calls `each(byte, escaped)` for every byte `text` stands for, each "%XX" decoded, until it returns false;
// false too for a '%' without two hex digits or a raw byte no path segment may hold ('/' is one unless
// `slashes`, for a whole path).
template <class Each>
bool for_each_byte(std::string_view text, bool slashes, Each each) {
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c != '%') {
      if (!raw_path_char(c) && !(slashes && c == '/')) return false;
      if (!each(c, false)) return false;
      continue;
    }
    const int decoded = escaped_byte(text, i);
    if (decoded < 0 || !each(static_cast<unsigned char>(decoded), true)) return false;
    i += 2;
  }
  return true;
}

}  // namespace

std::string url_segment_encode(std::string_view name) {
  std::string out;
  out.reserve(name.size());
  for (const char ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (unreserved(c)) out += ch;
    else append_escaped(out, c);
  }
  return out;
}

std::optional<std::string> url_segment_decode(std::string_view segment) {
  std::string out;
  out.reserve(segment.size());
  const bool read = for_each_byte(segment, false, [&out](unsigned char c, bool escaped) {
    if (escaped && (c == '/' || c == '\0')) return false;
    out += char(c);
    return true;
  });
  return read ? std::optional(std::move(out)) : std::nullopt;
}

std::optional<std::string> url_path_normalize(std::string_view path) {
  std::string out;
  out.reserve(path.size());
  const bool read = for_each_byte(path, true, [&out](unsigned char c, bool escaped) {
    if (escaped && !unreserved(c)) append_escaped(out, c);
    else out += char(c);
    return true;
  });
  return read ? std::optional(std::move(out)) : std::nullopt;
}

bool is_model_version(std::string_view text) {
  return text.size() == kModelVersionChars &&
         text.find_first_not_of("0123456789abcdef") == std::string_view::npos;
}

std::string model_version_text(uint64_t hash) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string text(kModelVersionChars, '0');
  for (size_t i = 0; i < kModelVersionChars; ++i) text[i] = kHex[(hash >> (60 - 4 * i)) & 15];
  return text;
}

std::string model_path(std::string_view name, std::string_view version) {
  std::string path = "/models/" + url_segment_encode(name);
  path += '/';
  path += version;
  return path;
}

std::optional<uint16_t> parse_port(std::string_view digits) {
  if (digits.empty() || digits.size() > 5) return std::nullopt;
  uint32_t value = 0;
  for (char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
    value = value * 10 + uint32_t(c - '0');
  }
  if (value == 0 || value > 65535) return std::nullopt;
  return uint16_t(value);
}

}  // namespace pms::protocol
