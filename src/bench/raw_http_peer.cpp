#include "bench/raw_http_peer.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>

namespace pms::bench {
namespace {

int milliseconds_left(AttackClock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - AttackClock::now()).count();
  return int(std::clamp<long long>(left, 0, 60000));
}

sockaddr_in ipv4(const std::string& address, uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  inet_pton(AF_INET, address.c_str(), &a.sin_addr);
  return a;
}

bool lowercase_equal(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  return true;
}

// The Content-Length of a response head, 0 when it has none.
uint64_t content_length(std::string_view head) {
  for (size_t line = head.find("\r\n"); line != std::string_view::npos; line = head.find("\r\n", line + 2)) {
    const std::string_view field = head.substr(line + 2, head.find("\r\n", line + 2) - (line + 2));
    const size_t colon = field.find(':');
    if (colon == std::string_view::npos || !lowercase_equal(field.substr(0, colon), "content-length")) continue;
    return std::strtoull(std::string(field.substr(colon + 1)).c_str(), nullptr, 10);
  }
  return 0;
}

}  // namespace

void ResponseCounter::feed(std::string_view bytes) {
  while (!bytes.empty() && !broken_) {
    if (in_body_) {
      const size_t n = size_t(std::min<uint64_t>(body_left_, bytes.size()));
      body_left_ -= n;
      bytes.remove_prefix(n);
      in_body_ = body_left_ > 0;
      continue;
    }
    const size_t before = head_text_.size();
    head_text_.append(bytes);
    const size_t end = head_text_.find("\r\n\r\n");
    if (end == std::string::npos) {
      broken_ = head_text_.size() > 65536;
      return;
    }
    bytes.remove_prefix(end + 4 - before);
    head_text_.resize(end + 2);
    if (head_text_.compare(0, 7, "HTTP/1.") != 0 || head_text_.size() < 12) {
      broken_ = true;
      return;
    }
    const int status = std::atoi(head_text_.c_str() + 9);
    statuses_.push_back(status);
    body_left_ = head_ || status == 304 || status < 200 ? 0 : content_length(head_text_);
    in_body_ = body_left_ > 0;
    head_text_.clear();
  }
}

RawHttpPeer::RawHttpPeer(const std::string& source, uint16_t port, AttackClock::time_point deadline, int receive_buffer,
                         bool head)
    : answers_(head) {
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return;
  if (receive_buffer > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  const sockaddr_in from = ipv4(source, 0), to = ipv4("127.0.0.1", port);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&from), sizeof from) != 0) return;
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&to), sizeof to) != 0 && errno != EINPROGRESS) return;
  short got = 0;
  if (!wait_for(POLLOUT, deadline, &got)) return;
  int error = 0;
  socklen_t length = sizeof error;
  ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &error, &length);
  connected_ = error == 0;
}

RawHttpPeer::~RawHttpPeer() {
  if (fd_ >= 0) ::close(fd_);
}

bool RawHttpPeer::wait_for(short events, AttackClock::time_point deadline, short* got) {
  for (;;) {
    pollfd fd{fd_, events, 0};
    const int ready = ::poll(&fd, 1, milliseconds_left(deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (got) *got = fd.revents;
    return ready > 0;
  }
}

void RawHttpPeer::note_end(int error) {
  ended_ = true;
  reset_ = reset_ || error == ECONNRESET || error == EPIPE;
}

bool RawHttpPeer::send(std::string_view bytes, AttackClock::time_point deadline) {
  while (!bytes.empty() && connected() && !ended_) {
    const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n > 0) {
      bytes.remove_prefix(size_t(n));
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      note_end(errno);
      return false;
    }
    if (!wait_for(POLLOUT, deadline)) return false;
  }
  return bytes.empty();
}

size_t RawHttpPeer::read(AttackClock::time_point deadline, size_t max) {
  if (!connected() || ended_ || !wait_for(POLLIN, deadline)) return 0;
  char buffer[16384];
  size_t total = 0;
  while (max == 0 || total < max) {
    const size_t room = max == 0 ? sizeof buffer : std::min(sizeof buffer, max - total);
    const ssize_t n = ::recv(fd_, buffer, room, 0);
    if (n > 0) {
      answers_.feed(std::string_view(buffer, size_t(n)));
      total += size_t(n);
      continue;
    }
    if (n == 0) note_end(0);
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) note_end(errno);
    break;
  }
  return total;
}

bool RawHttpPeer::read_answers(size_t answers, AttackClock::time_point deadline) {
  while (answers_.statuses().size() < answers && !ended_ && !answers_.broken() && AttackClock::now() < deadline)
    read(deadline);
  return answers_.statuses().size() >= answers;
}

bool RawHttpPeer::wait_closed(AttackClock::time_point deadline) {
  while (!ended_ && connected() && AttackClock::now() < deadline) read(deadline);
  return ended_;
}

bool RawHttpPeer::wait_ended_unread(AttackClock::time_point deadline) {
  short got = 0;
  if (!connected() || !wait_for(POLLRDHUP, deadline, &got)) return false;
  int error = 0;
  socklen_t length = sizeof error;
  ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &error, &length);
  note_end(error);
  return true;
}

}  // namespace pms::bench
