#include "client/external_http_transport.h"

#include <algorithm>
#include <utility>

#include "client/transport.h"
#include "common/error.h"

namespace pms::client {

// A GET request line and the few headers a browser adds, as an estimate of the bytes up: the page cannot
// see its own request on the wire.
constexpr uint64_t kRequestOverheadBytes = 64;

ExternalHttpTransport::ExternalHttpTransport(uint32_t in_flight, uint64_t max_body)
    : in_flight_(in_flight), max_body_(max_body) {
  if (in_flight == 0) fail("http", "at least one GET must be allowed in flight");
}

std::vector<ExternalHttpTransport::Get> ExternalHttpTransport::take_gets() { return std::exchange(outgoing_, {}); }

void ExternalHttpTransport::post(const std::string& target) {
  if (room() == 0) fail("http", "post() with no room: " + std::to_string(in_flight_) + " GETs pending");
  Pending p;
  p.id = next_id_++;
  p.answer.sent_at = Clock::now();
  pending_.push_back(std::move(p));
  outgoing_.push_back({pending_.back().id, target});
  ++counters_.requests;
  counters_.bytes_up += target.size() + kRequestOverheadBytes;
}

ExternalHttpTransport::Pending* ExternalHttpTransport::find(uint32_t id) {
  for (Pending& p : pending_)
    if (p.id == id) return p.done ? nullptr : &p;
  return nullptr;
}

void ExternalHttpTransport::deliver(uint32_t id, int status, std::vector<uint8_t> body, uint64_t wire_bytes) {
  Pending* p = find(id);
  if (!p) fail("http", "an answer to GET " + std::to_string(id) + ", which is not pending");
  if (body.size() > max_body_) fail("http", "an answer of " + std::to_string(body.size()) + " bytes, over the limit");
  counters_.payload_down += body.size();
  counters_.bytes_down += std::max<uint64_t>(wire_bytes, body.size());
  counters_.last_answer_ms = std::chrono::duration<double, std::milli>(Clock::now() - p->answer.sent_at).count();
  p->answer.status = status;
  p->answer.body = std::move(body);
  p->done = true;
}

void ExternalHttpTransport::fail_get(uint32_t id, const std::string& reason) {
  Pending* p = find(id);
  if (!p) fail("http", "a failure of GET " + std::to_string(id) + ", which is not pending");
  p->failure = reason;
  p->done = true;
}

std::optional<HttpAnswer> ExternalHttpTransport::take() {
  if (pending_.empty() || !pending_.front().done) return std::nullopt;
  Pending front = std::move(pending_.front());
  pending_.pop_front();
  if (front.failure) throw ConnectionError(*front.failure);
  return std::move(front.answer);
}

void ExternalHttpTransport::wait() {
  fail("http", "this transport cannot wait: its answers are delivered from outside");
}

}  // namespace pms::client
