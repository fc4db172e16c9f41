// Who a request comes from, as the HTTP server's per-address limits see it (docs/operating.md, "HTTP"):
// an IP address (IPv4 held as IPv4-mapped IPv6, so one type covers both), the ranges of trusted proxies
// given with --trusted-proxy, and the client named by a trusted proxy's X-Forwarded-For. Text in, no
// sockets: the transport hands in the peer's address and the header's value.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pms::server {

struct ClientAddress {
  std::array<uint8_t, 16> bytes{};  // network order; IPv4 as ::ffff:a.b.c.d

  bool operator==(const ClientAddress&) const = default;
  std::string text() const;  // "a.b.c.d" for IPv4, RFC 5952's form for IPv6
};

struct ClientAddressHash {
  size_t operator()(const ClientAddress& address) const;
};

// "a.b.c.d" or an IPv6 address (no brackets, no zone); nullopt for anything else.
std::optional<ClientAddress> parse_client_address(std::string_view text);

// A set of address ranges ("10.0.0.0/8", "::1/128", or a bare address for one host).
class AddressRanges {
 public:
  // Throws pms::Error naming `option` and the bad entry.
  static AddressRanges parse(const std::vector<std::string>& cidrs, const std::string& option);

  bool contains(const ClientAddress& address) const;
  bool empty() const { return ranges_.empty(); }

 private:
  struct Range {
    ClientAddress prefix;  // its bits past `bits` are zero
    unsigned bits = 0;     // of the 128; an IPv4 /n is 96 + n
  };
  std::vector<Range> ranges_;
};

// The client a request comes from: the peer itself, unless the peer is a trusted proxy and the request
// says whom it forwards. Then the rightmost X-Forwarded-For entry that is not itself a trusted proxy
// (RFC 7239 §5.2's reasoning: only the entries the trusted hops appended can be believed); the peer
// again when the header is absent or an entry it would take is not an address.
ClientAddress forwarded_client(const ClientAddress& peer, const AddressRanges& trusted,
                               std::string_view x_forwarded_for);

}  // namespace pms::server
