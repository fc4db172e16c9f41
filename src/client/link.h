// The TCP transport of a client: one connection owned by its own I/O thread, every wait under a deadline.
#pragma once
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "client/transport.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"

namespace pms::client {

// A Link's limits. Every wait on the server has one: a peer that stops answering, reading or sending
// mid-frame is a ConnectionError after its deadline, never a hang.
struct LinkOptions {
  std::chrono::milliseconds connect_timeout{5000};  // resolve + TCP handshake
  std::chrono::milliseconds write_timeout{10000};   // a queued frame's bytes make no progress this long
  std::chrono::milliseconds read_timeout{30000};    // a frame that has begun arriving is not complete
  size_t max_queued_bytes = 64u << 20;              // received payloads waiting for receive()
  uint32_t max_message = protocol::kDefaultMaxMessage;
  // Frames waiting to be written; one more frame over it means the server stopped reading. A frame
  // into an empty queue always fits, so this bounds the backlog, not a single (OPEN) frame.
  size_t max_send_queue_bytes = 16u << 20;
};

// A TCP connection owned by its own I/O thread: connect, reads and writes all run there (asio's
// chat_client shape). Received frames wait in a bounded queue (the socket is not read while it is full,
// so a slow consumer back-pressures the server instead of growing memory); sent frames wait in a bounded
// queue and go out one after another. A failed connect, a lost connection or a missed deadline surfaces
// as ConnectionError; close() and the destructor stop and join the thread without waiting on the server.
class Link : public Transport {
 public:
  Link(const std::string& host, uint16_t port, const LinkOptions& options = {});
  Link(const std::string& host, uint16_t port, size_t max_queued_bytes,
       uint32_t max_message = protocol::kDefaultMaxMessage);
  ~Link() override;
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  void send(const std::vector<uint8_t>& frame) override;
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override;
  LinkCounters counters() const override;
  void close();

  struct Core;  // link_core.h: the thread, the queues and the stream

 protected:
  // Starts `core`'s thread and connects it to host:port (then `path`, for a stream over HTTP); `what`
  // names the server in the ConnectionError thrown when it cannot connect.
  Link(std::unique_ptr<Core> core, const std::string& host, uint16_t port, const std::string& path,
       const std::string& what);

 private:
  std::unique_ptr<Core> core_;
};

}  // namespace pms::client
