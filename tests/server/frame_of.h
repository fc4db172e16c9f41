// Test-only: the one frame an encoded message is, as a session reads it (a test that drives a Session
// directly, without a socket).
#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "protocol/framing.h"

namespace pms::test {

inline protocol::Frame frame_of(const std::vector<uint8_t>& bytes) {
  protocol::FrameReader reader;
  reader.feed(bytes.data(), bytes.size());
  protocol::Frame frame;
  EXPECT_TRUE(reader.next(frame));
  return frame;
}

}  // namespace pms::test
