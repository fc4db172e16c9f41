// The frame reader over a byte stream cut anywhere: 1-byte chunks, several frames per chunk, limits
// enforced from the header alone, sticky failure, and a stream cut mid-frame.
#include <gtest/gtest.h>

#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol_fixtures.h"

namespace pms::protocol {
namespace {

using test::expect_rejected;

std::vector<uint8_t> sample_stream() {
  std::vector<uint8_t> stream;
  for (const std::vector<uint8_t>& frame :
       {encode(Hello{kProtocolVersion, "client"}), encode(List{}), encode(Open{"bunny", {}}),
        encode(ErrorMessage{ErrorCode::server_full, std::string(3000, 'x')}), encode(Close{})})
    stream.insert(stream.end(), frame.begin(), frame.end());
  return stream;
}

std::vector<Frame> read_all(FrameReader& reader) {
  std::vector<Frame> frames;
  Frame frame;
  while (reader.next(frame)) frames.push_back(frame);
  return frames;
}

void expect_sample_frames(const std::vector<Frame>& frames) {
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[0].type, MessageType::hello);
  EXPECT_EQ(decode_hello(frames[0].payload).client_name, "client");
  EXPECT_EQ(frames[1].type, MessageType::list);
  EXPECT_TRUE(frames[1].payload.empty());
  EXPECT_EQ(decode_open(frames[2].payload).model, "bunny");
  EXPECT_EQ(decode_error(frames[3].payload).text.size(), 3000u);
  EXPECT_EQ(frames[4].type, MessageType::close);
}

TEST(Framing, OneByteChunks) {
  const std::vector<uint8_t> stream = sample_stream();
  FrameReader reader;
  std::vector<Frame> frames;
  for (size_t i = 0; i < stream.size(); ++i) {
    reader.feed(&stream[i], 1);
    for (Frame& f : read_all(reader)) frames.push_back(std::move(f));
    // mid_frame() is false exactly at frame boundaries.
    if (i + 1 == stream.size()) {
      EXPECT_FALSE(reader.mid_frame());
    }
  }
  expect_sample_frames(frames);
}

TEST(Framing, WholeStreamAndRandomChunks) {
  const std::vector<uint8_t> stream = sample_stream();
  FrameReader whole;
  whole.feed(stream);
  EXPECT_EQ(whole.ready(), 5u);
  expect_sample_frames(read_all(whole));

  for (uint64_t seed = 1; seed <= 20; ++seed) {
    test::Rng rng(seed);
    FrameReader reader;
    for (size_t at = 0; at < stream.size();) {
      const size_t take = std::min<size_t>(stream.size() - at, 1 + rng() % 700);
      reader.feed(stream.data() + at, take);
      at += take;
    }
    expect_sample_frames(read_all(reader));
  }
}

TEST(Framing, MidFrameWhenCut) {
  const std::vector<uint8_t> frame = encode(Hello{kProtocolVersion, "client"});
  FrameReader reader;
  EXPECT_FALSE(reader.mid_frame());
  reader.feed(frame.data(), 3);  // inside the header
  EXPECT_TRUE(reader.mid_frame());
  reader.feed(frame.data() + 3, 4);  // inside the payload
  EXPECT_TRUE(reader.mid_frame());
  Frame out;
  EXPECT_FALSE(reader.next(out));
  reader.feed(frame.data() + 7, frame.size() - 7);
  EXPECT_FALSE(reader.mid_frame());
  EXPECT_TRUE(reader.next(out));
}

TEST(Framing, LimitIsCheckedFromTheHeaderAlone) {
  FrameReader reader(100);
  // Exactly the limit passes.
  std::vector<uint8_t> ok = {100, 0, 0, 0, uint8_t(MessageType::error)};
  ok.resize(ok.size() + 100, 0);
  reader.feed(ok);
  EXPECT_EQ(reader.ready(), 1u);

  // One over: refused on the 5th header byte, before any payload arrives. The frame before it is still
  // handed out first: errors surface in stream order.
  const uint8_t over[] = {101, 0, 0, 0, uint8_t(MessageType::base)};
  reader.feed(over, 4);
  EXPECT_FALSE(reader.failed());
  reader.feed(over + 4, 1);
  EXPECT_TRUE(reader.failed());
  Frame frame;
  ASSERT_TRUE(reader.next(frame));
  EXPECT_EQ(frame.payload.size(), 100u);
  expect_rejected([&] { reader.next(frame); }, ErrorCode::too_large,
                  "BASE announces 101 payload bytes, the limit is 100");
  // Sticky: later bytes are ignored, the error stays.
  reader.feed(ok);
  expect_rejected([&] { reader.next(frame); }, ErrorCode::too_large, "limit is 100");
}

TEST(Framing, ErrorAfterFramesInTheSameChunk) {
  std::vector<uint8_t> stream = sample_stream();
  const uint8_t over[] = {0xFF, 0xFF, 0xFF, 0xFF, 0x83};
  stream.insert(stream.end(), over, over + sizeof over);
  FrameReader reader;
  reader.feed(stream);
  std::vector<Frame> frames;
  Frame frame;
  try {
    while (reader.next(frame)) frames.push_back(frame);
    ADD_FAILURE() << "no error";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(e.code, ErrorCode::too_large);
    EXPECT_NE(std::string(e.what()).find("4294967295"), std::string::npos) << e.what();
  }
  expect_sample_frames(frames);
}

TEST(Framing, HugeAnnouncedSizeAllocatesNothingUpFront) {
  // 16 MiB announced and allowed, 10 bytes sent: the reader holds 10 bytes (the frame is not complete).
  FrameReader lenient;
  const uint8_t big[] = {0, 0, 0, 1, 0x83, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  lenient.feed(big, sizeof big);
  EXPECT_TRUE(lenient.mid_frame());
  EXPECT_EQ(lenient.ready(), 0u);
  EXPECT_FALSE(lenient.failed());
}

TEST(Framing, UnknownTypesAreFramedAndLeftToTheDecoders) {
  FrameReader reader;
  const uint8_t frame[] = {2, 0, 0, 0, 0x42, 7, 8};
  reader.feed(frame, sizeof frame);
  Frame out;
  ASSERT_TRUE(reader.next(out));
  EXPECT_EQ(uint8_t(out.type), 0x42);
  EXPECT_EQ(out.payload, (std::vector<uint8_t>{7, 8}));
  EXPECT_EQ(to_string(out.type), "type 0x42");
}

}  // namespace
}  // namespace pms::protocol
