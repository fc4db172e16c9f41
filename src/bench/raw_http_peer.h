// One hostile HTTP client on a raw non-blocking socket bound to its own loopback address (127.0.0.2 and
// up), so that the server's per-address limits see it as the host it pretends to be. It can drip bytes,
// stop reading, or read a little at a time; it counts the answers it reads by status. Every wait takes a
// deadline: a server that hangs ends the attacker's round, never the attacker.
#pragma once
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pms::bench {

using AttackClock = std::chrono::steady_clock;

// The answers in a byte stream, told apart by their Content-Length (no body for HEAD or 304).
class ResponseCounter {
 public:
  explicit ResponseCounter(bool head = false) : head_(head) {}
  void feed(std::string_view bytes);
  const std::vector<int>& statuses() const { return statuses_; }  // of the answers whole so far, in order
  bool broken() const { return broken_; }                         // something that is not HTTP/1.x came

 private:
  bool head_;
  std::string head_text_;
  uint64_t body_left_ = 0;
  bool in_body_ = false, broken_ = false;
  std::vector<int> statuses_;
};

class RawHttpPeer {
 public:
  // Connects from `source` to 127.0.0.1:port within `deadline`; a receive buffer given is set before the
  // connect, so the TCP window stays small. connected() says whether it worked.
  RawHttpPeer(const std::string& source, uint16_t port, AttackClock::time_point deadline, int receive_buffer = 0,
              bool head = false);
  ~RawHttpPeer();
  RawHttpPeer(const RawHttpPeer&) = delete;
  RawHttpPeer& operator=(const RawHttpPeer&) = delete;

  bool connected() const { return fd_ >= 0 && connected_; }
  // All of `bytes`; false when the connection ended or the deadline passed first.
  bool send(std::string_view bytes, AttackClock::time_point deadline);
  // Waits for bytes until `deadline` and reads at most `max` of them (0: all there are); the bytes read.
  size_t read(AttackClock::time_point deadline, size_t max = 0);
  // Reads until `answers` answers are whole, the connection ends or the deadline passes: true for the first.
  bool read_answers(size_t answers, AttackClock::time_point deadline);
  // Reads and drops until the server ends the connection; false when the deadline passes first.
  bool wait_closed(AttackClock::time_point deadline);
  // Waits, reading nothing, until the server ends the connection (an RST, or its FIN behind unread bytes);
  // false when the deadline passes first.
  bool wait_ended_unread(AttackClock::time_point deadline);

  bool ended() const { return ended_; }  // the server closed or reset the connection
  bool reset() const { return reset_; }  // ... with an RST
  const ResponseCounter& answers() const { return answers_; }

 private:
  bool wait_for(short events, AttackClock::time_point deadline, short* got = nullptr);
  void note_end(int error);

  int fd_ = -1;
  bool connected_ = false, ended_ = false, reset_ = false;
  ResponseCounter answers_;
};

}  // namespace pms::bench
