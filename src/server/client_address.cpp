#include "server/client_address.h"

#include <arpa/inet.h>

#include <algorithm>
#include <cstring>

#include "common/error.h"

namespace pms::server {
namespace {

constexpr std::array<uint8_t, 12> kMappedPrefix = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF};

bool is_ipv4(const ClientAddress& address) {
  return std::equal(kMappedPrefix.begin(), kMappedPrefix.end(), address.bytes.begin());
}

std::string_view trimmed(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

// Zeroes every bit of `address` past the first `bits`.
ClientAddress masked(ClientAddress address, unsigned bits) {
  for (unsigned i = 0; i < 16; ++i) {
    const unsigned kept = bits > 8 * i ? std::min(8u, bits - 8 * i) : 0;
    address.bytes[i] &= uint8_t(0xFF00u >> kept);
  }
  return address;
}

[[noreturn]] void refuse_range(const std::string& option, const std::string& cidr, const std::string& why) {
  fail(option, "'" + cidr + "' is not " + why);
}

bool is_decimal(std::string_view text) {
  return !text.empty() && text.size() <= 3 && std::all_of(text.begin(), text.end(), [](char c) {
    return c >= '0' && c <= '9';
  });
}

}  // namespace

std::string ClientAddress::text() const {
  char out[INET6_ADDRSTRLEN] = {};
  if (is_ipv4(*this)) {
    inet_ntop(AF_INET, bytes.data() + 12, out, sizeof out);
  } else {
    inet_ntop(AF_INET6, bytes.data(), out, sizeof out);
  }
  return out;
}

size_t ClientAddressHash::operator()(const ClientAddress& address) const {
  uint64_t high, low;
  std::memcpy(&high, address.bytes.data(), 8);
  std::memcpy(&low, address.bytes.data() + 8, 8);
  // Per-address state is keyed by what a peer chooses: mix both halves so that no prefix collides.
  return size_t((high * 0x9E3779B97F4A7C15ull) ^ (low + 0x632BE59BD9B4E019ull + (high << 6) + (high >> 2)));
}

std::optional<ClientAddress> parse_client_address(std::string_view text) {
  if (text.empty() || text.size() >= INET6_ADDRSTRLEN) return std::nullopt;
  char buffer[INET6_ADDRSTRLEN] = {};
  std::memcpy(buffer, text.data(), text.size());
  ClientAddress address;
  if (inet_pton(AF_INET, buffer, address.bytes.data() + 12) == 1) {
    std::copy(kMappedPrefix.begin(), kMappedPrefix.end(), address.bytes.begin());
    return address;
  }
  if (inet_pton(AF_INET6, buffer, address.bytes.data()) == 1) return address;
  return std::nullopt;
}

AddressRanges AddressRanges::parse(const std::vector<std::string>& cidrs, const std::string& option) {
  AddressRanges ranges;
  for (const std::string& cidr : cidrs) {
    const size_t slash = cidr.find('/');
    const std::optional<ClientAddress> address = parse_client_address(std::string_view(cidr).substr(0, slash));
    if (!address) refuse_range(option, cidr, "an IP address or a CIDR range (a.b.c.d/n or an IPv6 prefix/n)");
    const unsigned family_bits = is_ipv4(*address) ? 32 : 128;
    unsigned bits = family_bits;
    if (slash != std::string::npos) {
      const std::string length = cidr.substr(slash + 1);
      if (!is_decimal(length) || std::stoul(length) > family_bits)
        refuse_range(option, cidr, "a CIDR range: its prefix length must be 0 to " + std::to_string(family_bits));
      bits = unsigned(std::stoul(length));
    }
    if (family_bits == 32) bits += 96;
    ranges.ranges_.push_back({masked(*address, bits), bits});
  }
  return ranges;
}

bool AddressRanges::contains(const ClientAddress& address) const {
  return std::any_of(ranges_.begin(), ranges_.end(),
                     [&](const Range& range) { return masked(address, range.bits) == range.prefix; });
}

ClientAddress forwarded_client(const ClientAddress& peer, const AddressRanges& trusted,
                               std::string_view x_forwarded_for) {
  if (!trusted.contains(peer)) return peer;
  ClientAddress client = peer;
  while (!x_forwarded_for.empty()) {
    const size_t comma = x_forwarded_for.rfind(',');
    const std::string_view entry =
        trimmed(comma == std::string_view::npos ? x_forwarded_for : x_forwarded_for.substr(comma + 1));
    x_forwarded_for = comma == std::string_view::npos ? std::string_view() : x_forwarded_for.substr(0, comma);
    const std::optional<ClientAddress> hop = parse_client_address(entry);
    if (!hop) return client;  // not an address: nothing left of it can be believed
    client = *hop;
    if (!trusted.contains(client)) return client;
  }
  return client;
}

}  // namespace pms::server
