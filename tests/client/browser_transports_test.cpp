// What the browser's viewers take from outside is hostile like any peer's: ExternalHttpTransport refuses
// answers to GETs it did not post, twice, or over its body limit, hands answers over in request order
// whatever order they come in, and never waits; MessageSessionViewer refuses a frame announced over the
// limit and anything but HELLO_OK first, and sends nothing without a connection.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "client/external_http_transport.h"
#include "client/message_session_viewer.h"
#include "client/transport.h"
#include "common/error.h"
#include "protocol/message_types.h"

namespace pms {
namespace {

using client::ExternalHttpTransport;

TEST(ExternalHttpTransport, AnswersComeInRequestOrderWhateverOrderTheyArrive) {
  ExternalHttpTransport http(3);
  http.post("/a");
  http.post("/b");
  http.post("/c");
  EXPECT_EQ(http.room(), 0u);
  EXPECT_THROW(http.post("/d"), Error) << "no room: the pipe is the client's to respect";
  const std::vector<ExternalHttpTransport::Get> gets = http.take_gets();
  ASSERT_EQ(gets.size(), 3u);
  EXPECT_EQ(gets[1].target, "/b");
  EXPECT_TRUE(http.take_gets().empty()) << "each GET is handed out once";
  http.deliver(gets[2].id, 200, {3});
  http.deliver(gets[1].id, 200, {2});
  EXPECT_FALSE(http.take()) << "the first answer is not in: none can be taken";
  http.deliver(gets[0].id, 404, {1});
  for (uint8_t expected = 1; expected <= 3; ++expected) {
    const std::optional<client::HttpAnswer> answer = http.take();
    ASSERT_TRUE(answer);
    EXPECT_EQ(answer->body, std::vector<uint8_t>{expected});
  }
  EXPECT_EQ(http.pending(), 0u);
  EXPECT_EQ(http.counters().payload_down, 3u);
  EXPECT_EQ(http.counters().requests, 3u);
  EXPECT_THROW(http.wait(), Error) << "it cannot block";
}

TEST(ExternalHttpTransport, RefusesAnswersToNothingTwiceOrOverTheLimit) {
  ExternalHttpTransport http(2, 16);
  http.post("/a");
  http.post("/b");
  const std::vector<ExternalHttpTransport::Get> gets = http.take_gets();
  EXPECT_THROW(http.deliver(999, 200, {}), Error);
  EXPECT_THROW(http.deliver(gets[0].id, 200, std::vector<uint8_t>(17)), Error);
  http.deliver(gets[0].id, 200, {});
  EXPECT_THROW(http.deliver(gets[0].id, 200, {}), Error) << "answered twice";
  http.fail_get(gets[1].id, "GET /b: network down");
  EXPECT_TRUE(http.take());
  EXPECT_THROW(http.take(), client::ConnectionError) << "a GET the outside gave up on";
}

TEST(MessageSessionViewer, SendsNothingUnconnectedAndRefusesWhatAServerMustNotSend) {
  client::ClientOptions options;
  client::MessageSessionViewer viewer(options, "terrain");
  EXPECT_TRUE(viewer.frame(Camera{}).opening);
  EXPECT_TRUE(viewer.take_outgoing().empty());
  viewer.on_bytes(std::vector<uint8_t>{1, 2, 3});  // a closed socket's last bytes: ignored
  viewer.connected();
  EXPECT_EQ(viewer.take_outgoing().size(), 2u) << "HELLO and OPEN together";

  // A BASE before HELLO_OK: refused.
  viewer.on_bytes(std::vector<uint8_t>{0, 0, 0, 0, uint8_t(protocol::MessageType::base)});
  EXPECT_THROW(viewer.frame(Camera{}), Error);

  // A frame announced over the limit: refused once its header is in, nothing allocated for it.
  client::MessageSessionViewer other(options, "terrain");
  other.connected();
  other.on_bytes(std::vector<uint8_t>{0xFF, 0xFF, 0xFF, 0x7F, uint8_t(protocol::MessageType::vsplits)});
  EXPECT_THROW(other.frame(Camera{}), Error);
}

}  // namespace
}  // namespace pms
