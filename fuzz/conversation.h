// What the conversation fuzz targets share (fuzz_http_conversation, fuzz_ws_conversation): a byte string
// written to a real server's socket in chunks an input chooses, whatever comes back read meanwhile, then the
// end of the stream, and whether the server ended the conversation in time.
#pragma once
#include <poll.h>
#include <sys/socket.h>

#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace fuzz_conversation {

using Clock = std::chrono::steady_clock;

// A small generator for the chunk sizes, from the input's first two bytes.
struct Chunks {
  uint32_t state;
  size_t next() {
    state = state * 1103515245u + 12345u;
    const uint32_t r = state >> 16;
    return (r % 4 == 0) ? 1 + r % 3 : 1 + r % 700;  // single bytes now and then: split tokens, split CRLFs
  }
};

// Writes the conversation in chunks, reading whatever comes meanwhile, then half-closes and reads to the
// end; false when the server did not end the conversation within `deadline`.
inline bool converse(int fd, std::string_view bytes, Chunks chunks, std::string& received, Clock::time_point deadline) {
  bool write_closed = false;
  char buffer[65536];
  while (Clock::now() < deadline) {
    if (!bytes.empty()) {
      const size_t n = std::min(bytes.size(), chunks.next());
      const ssize_t sent = ::send(fd, bytes.data(), n, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (sent > 0) bytes.remove_prefix(size_t(sent));
      if (sent < 0 && errno != EAGAIN && errno != EWOULDBLOCK) return true;  // the server closed it first
    } else if (!write_closed) {
      ::shutdown(fd, SHUT_WR);
      write_closed = true;
    }
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, bytes.empty() ? 50 : 0) <= 0) continue;
    const ssize_t got = ::recv(fd, buffer, sizeof buffer, MSG_DONTWAIT);
    if (got == 0) return true;  // the server ended it
    if (got < 0 && errno != EAGAIN && errno != EWOULDBLOCK) return true;  // reset at a deadline
    if (got > 0) received.append(buffer, size_t(got));
  }
  return false;
}

}  // namespace fuzz_conversation
