// Model names in URL paths: one canonical escape per name, and a decoder that takes what RFC 3986 allows.
#include <gtest/gtest.h>

#include "protocol/url_segment.h"

namespace pms::protocol {
namespace {

// Every byte a file name can hold: all but NUL and '/'.
TEST(UrlSegment, EveryByteOfAFileNameRoundTripsAndOnlyUnreservedOnesStayRaw) {
  std::string all;
  for (int c = 1; c < 256; ++c)
    if (c != '/') all += char(c);
  const std::string encoded = url_segment_encode(all);
  EXPECT_EQ(encoded.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-._~%"),
            std::string::npos);
  EXPECT_EQ(url_segment_decode(encoded), all);
  EXPECT_EQ(url_segment_encode("bunny"), "bunny");
  EXPECT_EQ(url_segment_encode("my bunny 50%"), "my%20bunny%2050%25");
  EXPECT_EQ(url_segment_encode("\xC3\xBC"), "%C3%BC");
  EXPECT_EQ(model_path("my bunny", "0123456789abcdef"), "/models/my%20bunny/0123456789abcdef");
}

TEST(UrlSegment, AVersionHasOneSpelling) {
  EXPECT_TRUE(is_model_version("0123456789abcdef"));
  EXPECT_FALSE(is_model_version("0123456789ABCDEF"));  // upper case: another URL for the same version
  EXPECT_FALSE(is_model_version("0123456789abcde"));
  EXPECT_FALSE(is_model_version("0123456789abcdef0"));
  EXPECT_FALSE(is_model_version("base"));
}

TEST(UrlSegment, DecodingTakesEitherCaseAndRawPathCharacters) {
  EXPECT_EQ(url_segment_decode("%c3%BC"), "\xC3\xBC");
  EXPECT_EQ(url_segment_decode("bun%6Ey"), "bunny");
  EXPECT_EQ(url_segment_decode("a(1)+b,c;d=e:f@g!$&'*"), "a(1)+b,c;d=e:f@g!$&'*");
  EXPECT_EQ(url_segment_decode(""), "");
}

TEST(UrlSegment, MalformedSegmentsAreRejected) {
  for (const char* bad :
       {"%", "a%", "a%4", "%4g", "%g4", "a b", "a/b", "a?b", "a#b", "a\"b", "<x>", "%2F", "%2f", "%00", "\x80"})
    EXPECT_FALSE(url_segment_decode(bad).has_value()) << bad;
}

// RFC 3986 §6.2.2: one spelling per path, so a server can tell a second spelling of a URL from the first.
TEST(UrlSegment, APathsNormalFormDecodesUnreservedEscapesAndUpperCasesTheRest) {
  EXPECT_EQ(url_path_normalize("/models/%62unny/base"), "/models/bunny/base");
  EXPECT_EQ(url_path_normalize("/%6d%6F%64els/a%2db%2E%5F%7E%30"), "/models/a-b._~0");
  EXPECT_EQ(url_path_normalize("/models/my%20bunny%2f%c3%bc"), "/models/my%20bunny%2F%C3%BC");
  EXPECT_EQ(url_path_normalize("/models/a!b@c:d/splits/AZaz09-_"), "/models/a!b@c:d/splits/AZaz09-_");
  EXPECT_EQ(url_path_normalize("/%25%36%32"), "/%2562");  // an escaped '%' stays one: "%2562" is not "%62" or "b"
  EXPECT_EQ(url_path_normalize(""), "");
  for (const std::string once : {"/models/%62unny/base", "/models/my%20bunny%2f%c3%bc", "/%25%36%32"})
    EXPECT_EQ(url_path_normalize(*url_path_normalize(once)), url_path_normalize(once)) << once;
  for (const char* bad : {"/%", "/a%4", "/%4g", "/a b", "/a\"b", "/<x>", "/a?b", "/\x80"})
    EXPECT_FALSE(url_path_normalize(bad).has_value()) << bad;
}

}  // namespace
}  // namespace pms::protocol
