// What every HTTP transport shares (http_transport.h): the URL's parts, and the lock-step calls written
// once over the non-blocking ones.
#include "client/http_transport.h"

#include <exception>
#include <utility>

#include "common/error.h"
#include "protocol/url_segment.h"

namespace pms::client {

HttpUrl parse_http_url(const std::string& text, const std::string& where) {
  const std::string scheme = "http://";
  if (text.compare(0, scheme.size(), scheme) != 0) fail(where, "'" + text + "' is not http://HOST[:PORT][/prefix]");
  HttpUrl url;
  const std::string rest = text.substr(scheme.size());
  const size_t slash = rest.find('/');
  const std::string authority = rest.substr(0, slash);
  if (slash != std::string::npos) url.prefix = rest.substr(slash);
  while (!url.prefix.empty() && url.prefix.back() == '/') url.prefix.pop_back();
  if (url.prefix.find_first_of("?#") != std::string::npos) fail(where, "'" + text + "': no query or fragment");
  const size_t colon = authority.rfind(':');
  url.host = authority.substr(0, colon);
  if (url.host.empty()) fail(where, "'" + text + "' names no host");
  if (colon != std::string::npos) {
    const std::optional<uint16_t> port = protocol::parse_port(std::string_view(authority).substr(colon + 1));
    if (!port) fail(where, "'" + text + "' has no valid port");
    url.port = *port;
  }
  return url;
}

void HttpTransport::send(const std::string& target) {
  post(target);
  poll();
}

HttpAnswer HttpTransport::receive() {
  for (;;) {
    if (std::optional<HttpAnswer> answer = take()) return std::move(*answer);
    if (pending() == 0) fail("http", "receive() with no GET pending");
    wait();
  }
}

void HttpTransport::get_all(const std::vector<std::string>& targets, const OnAnswer& on_answer) {
  if (pending() != 0) fail("http", "get_all() with GETs of another caller pending");
  size_t sent = 0;
  for (size_t answered = 0; answered < targets.size(); ++answered) {
    while (sent < targets.size() && room() > 0) send(targets[sent++]);
    on_answer(answered, receive());
  }
}

std::vector<HttpAnswer> HttpTransport::get_all(const std::vector<std::string>& targets) {
  std::vector<HttpAnswer> answers(targets.size());
  get_all(targets, [&](size_t index, HttpAnswer&& answer) { answers[index] = std::move(answer); });
  return answers;
}

HttpAnswer HttpTransport::get(const std::string& target) {
  HttpAnswer out;
  get_all({target}, [&](size_t, HttpAnswer&& answer) { out = std::move(answer); });
  return out;
}

PendingGets::PendingGets(std::vector<std::string> targets) : targets_(std::move(targets)), answers_(targets_.size()) {}

bool PendingGets::advance(HttpTransport& http) {
  while (posted_ < targets_.size() && http.room() > 0) http.post(targets_[posted_++]);
  http.poll();
  while (answered_ < posted_)
    if (std::optional<HttpAnswer> answer = http.take()) answers_[answered_++] = std::move(*answer);
    else break;
  while (posted_ < targets_.size() && http.room() > 0) http.post(targets_[posted_++]);
  return answered_ == targets_.size();
}

}  // namespace pms::client
