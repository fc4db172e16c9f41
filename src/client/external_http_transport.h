// An HttpTransport whose I/O is done outside (the browser's fetch): post() queues a GET for the outside to
// take (take_gets), which fetches it however it can and hands each answer back (deliver) in any order;
// take() gives them out in request order, as every HttpTransport does. Nothing here waits: wait() throws,
// so only the free-running paths (frame(), the event-driven open) run over it.
// Shared with the browser build: no I/O, single-threaded.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "client/http_transport.h"

namespace pms::client {

class ExternalHttpTransport : public HttpTransport {
 public:
  using Clock = std::chrono::steady_clock;
  // At most `in_flight` GETs pending at once; an answer's body at most `max_body` bytes.
  explicit ExternalHttpTransport(uint32_t in_flight = 4, uint64_t max_body = 64u << 20);

  struct Get {
    uint32_t id = 0;
    std::string target;  // under the server's URL: the outside prepends it
  };
  // The GETs posted since the last call, for the outside to fetch.
  std::vector<Get> take_gets();
  // GET `id`'s answer. `wire_bytes`: what it cost on the wire as far as the outside can tell (0: the body
  // alone). pms::Error for an id not pending or answered twice, or a body over the limit.
  void deliver(uint32_t id, int status, std::vector<uint8_t> body, uint64_t wire_bytes = 0);
  // GET `id` could not be fetched (the outside gave up retrying): take() throws ConnectionError with
  // `reason` when it comes to it.
  void fail_get(uint32_t id, const std::string& reason);

  void post(const std::string& target) override;
  void poll() override {}
  std::optional<HttpAnswer> take() override;
  void wait() override;
  size_t pending() const override { return pending_.size(); }
  size_t room() const override { return pending_.size() < in_flight_ ? in_flight_ - pending_.size() : 0; }
  const HttpCounters& counters() const override { return counters_; }

 private:
  struct Pending {
    uint32_t id = 0;
    bool done = false;
    std::optional<std::string> failure;
    HttpAnswer answer;
  };
  Pending* find(uint32_t id);

  uint32_t in_flight_;
  uint64_t max_body_;
  uint32_t next_id_ = 1;
  std::deque<Pending> pending_;  // in request order
  std::vector<Get> outgoing_;
  HttpCounters counters_;
};

}  // namespace pms::client
