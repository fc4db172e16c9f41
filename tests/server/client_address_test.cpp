// Client addresses as the HTTP server's per-address limits key them: both families in one type, CIDR
// ranges, and whom a trusted proxy's X-Forwarded-For names.
#include <gtest/gtest.h>

#include "common/error.h"
#include "server/client_address.h"

namespace pms::server {
namespace {

ClientAddress address(const char* text) {
  const std::optional<ClientAddress> parsed = parse_client_address(text);
  EXPECT_TRUE(parsed) << text;
  return parsed.value_or(ClientAddress{});
}

TEST(ClientAddress, BothFamiliesParseAndPrintBack) {
  for (const char* text : {"127.0.0.1", "198.51.100.7", "::1", "2001:db8::42", "::ffff:10.0.0.1"})
    EXPECT_EQ(address(text), address(address(text).text().c_str())) << text;
  EXPECT_EQ(address("10.0.0.1"), address("::ffff:10.0.0.1"));  // IPv4 as IPv4-mapped IPv6
  EXPECT_EQ(address("10.0.0.1").text(), "10.0.0.1");
  for (const char* bad : {"", "10.0.0", "10.0.0.256", "host", "[::1]", "::1%eth0", "1.2.3.4 ", "10.0.0.1:80"})
    EXPECT_FALSE(parse_client_address(bad)) << bad;
}

TEST(ClientAddress, RangesHoldTheirPrefixOnly) {
  const AddressRanges ranges = AddressRanges::parse({"10.0.0.0/8", "192.0.2.7", "2001:db8::/32"}, "--trusted-proxy");
  EXPECT_TRUE(ranges.contains(address("10.255.1.2")));
  EXPECT_FALSE(ranges.contains(address("11.0.0.1")));
  EXPECT_TRUE(ranges.contains(address("192.0.2.7")));
  EXPECT_FALSE(ranges.contains(address("192.0.2.8")));
  EXPECT_TRUE(ranges.contains(address("2001:db8:ffff::1")));
  EXPECT_FALSE(ranges.contains(address("2001:db9::1")));
  EXPECT_TRUE(AddressRanges::parse({"0.0.0.0/0"}, "x").contains(address("203.0.113.1")));
  EXPECT_FALSE(AddressRanges::parse({"0.0.0.0/0"}, "x").contains(address("::1")));  // IPv4's /0 only
}

TEST(ClientAddress, BadRangesAreErrorsNamingTheOption) {
  for (const char* bad : {"10.0.0.0/33", "10.0.0.0/", "10.0.0.0/-1", "10.0.0.0/8/8", "::/129", "localhost", "1.2.3/8"}) {
    try {
      AddressRanges::parse({bad}, "--trusted-proxy");
      ADD_FAILURE() << bad << " was taken";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--trusted-proxy"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(ClientAddress, OnlyATrustedPeersForwardedForIsBelieved) {
  const AddressRanges proxies = AddressRanges::parse({"10.0.0.0/24"}, "--trusted-proxy");
  const ClientAddress proxy = address("10.0.0.5"), stranger = address("203.0.113.9");
  EXPECT_EQ(forwarded_client(stranger, proxies, "198.51.100.7"), stranger);  // anyone can write the header
  EXPECT_EQ(forwarded_client(proxy, proxies, ""), proxy);
  EXPECT_EQ(forwarded_client(proxy, proxies, "198.51.100.7"), address("198.51.100.7"));
  // The client wrote the first entry itself: the rightmost one that is not a trusted hop is the client.
  EXPECT_EQ(forwarded_client(proxy, proxies, "1.1.1.1, 198.51.100.7"), address("198.51.100.7"));
  EXPECT_EQ(forwarded_client(proxy, proxies, "198.51.100.7 ,10.0.0.9"), address("198.51.100.7"));
  EXPECT_EQ(forwarded_client(proxy, proxies, "garbage, 10.0.0.9"), address("10.0.0.9"));
  EXPECT_EQ(forwarded_client(proxy, proxies, "198.51.100.7, garbage"), proxy);
  EXPECT_EQ(forwarded_client(proxy, proxies, "2001:db8::1"), address("2001:db8::1"));
}

}  // namespace
}  // namespace pms::server
