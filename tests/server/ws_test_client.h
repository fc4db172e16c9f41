// Test-only: a blocking WebSocket client on Beast for the WebSocket's tests, and the raw pieces attacks
// are made of (frames written on the socket as they are, upgrades with chosen headers).
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "protocol/message_types.h"

namespace pms::test {

class WsTestClient {
 public:
  // Connects from `from` and upgrades /ws, with `origin` unless empty; throws when the upgrade fails.
  // `receive_buffer` > 0: SO_RCVBUF, set before connecting.
  explicit WsTestClient(uint16_t port, const std::string& origin = "", const std::string& from = "127.0.0.1",
                        int timeout_ms = 5000, int receive_buffer = 0);
  ~WsTestClient();

  void send_binary(const std::vector<uint8_t>& bytes);
  void send_text(const std::string& text);
  // Bytes written on the socket as they are (a frame built by ws_frame, or part of one); false when the
  // server ended the connection before it took them all.
  bool send_raw(const std::vector<uint8_t>& bytes);
  // The next message; nothing when the server closed the WebSocket or the read timed out.
  std::optional<std::vector<uint8_t>> read();
  // Reads until the server ends the WebSocket (true) or timeout_ms passes without it (false); the code of
  // the ERROR frame among the messages read, if any.
  bool closed_by_server(std::optional<protocol::ErrorCode>* error = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A client's frame (RFC 6455 §5.2), masked: `opcode` 1 text, 2 binary, 0 continuation, 9 ping.
std::vector<uint8_t> ws_frame(uint8_t opcode, bool fin, const std::vector<uint8_t>& payload);

// The status of the answer to GET /ws with the upgrade's headers and `extra` ones (an empty value
// leaves that header out).
int upgrade_status(uint16_t port, const std::map<std::string, std::string>& extra, const std::string& from = "127.0.0.1");

}  // namespace pms::test
