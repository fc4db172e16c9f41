// Number scanning shared by the hand-written ascii importers (PLY, OBJ, OFF); io layer internal.
// The big scans are tens of MB of text, so this avoids locale-aware strtod and istreams.
#pragma once
#include <fast_float/fast_float.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>

namespace pms::text {

// Whitespace inside a line; '\n' is separate because OBJ and OFF are line oriented.
inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
inline bool is_space(char c) { return is_blank(c) || c == '\n'; }

inline const char* skip_blanks(const char* p, const char* end) {
  while (p < end && is_blank(*p)) ++p;
  return p;
}
inline const char* skip_spaces(const char* p, const char* end) {
  while (p < end && is_space(*p)) ++p;
  return p;
}
inline const char* skip_token(const char* p, const char* end) {
  while (p < end && !is_space(*p)) ++p;
  return p;
}
inline const char* line_end(const char* p, const char* end) {
  const void* nl = std::memchr(p, '\n', size_t(end - p));
  return nl ? static_cast<const char*>(nl) : end;
}

// Parses a float or double at p; returns the end of the number, or nullptr when there is none.
// fast_float rounds correctly, so "0.1" as a float property reads as the nearest float.
template <class T>
const char* parse_real(const char* p, const char* end, T& out) {
  if (p < end && *p == '+') ++p;  // from_chars rejects the sign strtod accepts
  const auto result = fast_float::from_chars(p, end, out);
  return result.ec == std::errc() ? result.ptr : nullptr;
}

// Parses a decimal integer with optional sign; nullptr on no digits or overflow of int64.
inline const char* parse_int(const char* p, const char* end, int64_t& out) {
  bool negative = false;
  if (p < end && (*p == '-' || *p == '+')) negative = *p++ == '-';
  const char* digits = p;
  uint64_t value = 0;
  while (p < end && unsigned(*p - '0') < 10) {
    if (value > (uint64_t(INT64_MAX) - unsigned(*p - '0')) / 10) return nullptr;
    value = value * 10 + unsigned(*p++ - '0');
  }
  if (p == digits) return nullptr;
  out = negative ? -int64_t(value) : int64_t(value);
  return p;
}

// 1-based line of p, computed only when an error message needs it.
inline size_t line_number(const char* begin, const char* p) { return 1 + size_t(std::count(begin, p, '\n')); }

// The token at p, shortened for an error message.
inline std::string quote_token(const char* p, const char* end) {
  const char* stop = std::min(skip_token(p, end), p + 24);
  if (p == end) return "nothing";
  std::string token(p, stop);
  for (char& c : token)
    if (uint8_t(c) < 0x20 || uint8_t(c) >= 0x7f) c = '?';  // keep the error one printable line
  return "'" + token + "'";
}

}  // namespace pms::text
