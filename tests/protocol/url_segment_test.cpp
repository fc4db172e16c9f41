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
  EXPECT_EQ(model_path("my bunny"), "/models/my%20bunny");
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

}  // namespace
}  // namespace pms::protocol
