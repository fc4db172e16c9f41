#include "in_process_http.h"

#include <chrono>
#include <utility>

#include "common/error.h"
#include "server/http_routes.h"

namespace pms::test {

InProcessHttp::InProcessHttp(std::shared_ptr<const server::Catalogue> catalogue, uint32_t in_flight)
    : catalogue_(std::move(catalogue)), in_flight_(in_flight) {
  counters_.connections = 1;
}

void InProcessHttp::post(const std::string& target) {
  if (room() == 0) fail("in-process http", "more than in_flight GETs pending");
  posted_.push_back({target, std::chrono::steady_clock::now()});
  ++counters_.requests;
  counters_.bytes_up += ("GET " + target + " HTTP/1.1\r\n").size();
}

void InProcessHttp::poll() {
  while (!held_ && !posted_.empty()) answer_oldest();
}

std::optional<client::HttpAnswer> InProcessHttp::take() {
  if (arrived_.empty()) return std::nullopt;
  client::HttpAnswer answer = std::move(arrived_.front());
  arrived_.pop_front();
  return answer;
}

void InProcessHttp::wait() {
  if (!arrived_.empty()) return;
  if (posted_.empty()) fail("in-process http", "wait() with no GET pending");
  answer_oldest();
}

// Tables a resource needs and the catalogue has not built yet are built first and the GET routed again, as
// the HTTP server does (it waits under the request deadline; a build here ends, ready or failed, by itself).
void InProcessHttp::answer_oldest() {
  const Posted get = std::move(posted_.front());
  posted_.pop_front();
  const server::HttpRequest request{"GET", get.target, {}, ""};
  server::HttpAnswer routed = server::route(*catalogue_, limits_, request);
  if (routed.waits_for) {
    catalogue_->table_builds().wait(*routed.waits_for, routed.waits_for_mode);
    routed = server::route(*catalogue_, limits_, request);
  }
  server::finish_body(routed);
  client::HttpAnswer answer;
  answer.status = routed.status;
  answer.body.assign(routed.body().begin(), routed.body().end());
  answer.sent_at = get.at;
  counters_.bytes_down += answer.body.size();
  counters_.payload_down += answer.body.size();
  counters_.last_answer_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - get.at).count();
  arrived_.push_back(std::move(answer));
}

}  // namespace pms::test
