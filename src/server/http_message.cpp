// Beast's messages to and from the routes (http_message.h).
#include "server/http_message.h"

#include <string>

namespace pms::server {
namespace {

std::string_view view_of(boost::beast::string_view s) { return {s.data(), s.size()}; }

}  // namespace

void bound_parser(HttpParser& parser, const HttpLimits& limits) {
  parser.header_limit(limits.max_header_bytes);
  parser.body_limit(limits.max_body_bytes);
}

HttpAnswer parse_error_answer(const boost::beast::error_code& ec, std::string_view buffered) {
  if (ec == http::error::header_limit) {
    if (buffered.find("\r\n") == std::string_view::npos) return error_answer(414, "the request line is too long");
    return error_answer(431, "the request headers are too large");
  }
  if (ec == http::error::body_limit) return error_answer(413, "the request body is too large");
  return error_answer(400, "malformed HTTP request: " + ec.message());
}

HttpAnswer answer_request(const Catalogue& catalogue, const HttpLimits& limits,
                          const http::request<http::vector_body<uint8_t>>& request) {
  HttpRequest r;
  r.method = view_of(request.method_string());
  r.target = view_of(request.target());
  r.body = request.body();
  if (const auto it = request.find(http::field::if_none_match); it != request.end()) r.if_none_match = view_of(it->value());
  return route(catalogue, limits, r);
}

HttpResponse make_response(const HttpAnswer& answer, bool head, bool keep_alive, unsigned version) {
  HttpResponse response{http::int_to_status(unsigned(answer.status)), version};
  response.set(http::field::server, "pmstream");
  response.set(http::field::content_type, answer.content_type);
  if (!answer.etag.empty()) response.set(http::field::etag, answer.etag);
  response.set(http::field::cache_control, answer.cacheable ? "public, max-age=31536000, immutable" : "no-store");
  if (!answer.allow.empty()) response.set(http::field::allow, answer.allow);
  if (answer.status == 503) response.set(http::field::retry_after, "1");
  response.keep_alive(keep_alive);
  const std::span<const uint8_t> body = answer.body();
  if (answer.status == 304) return response;  // no body and no length (RFC 9110 §15.4.5)
  if (head) {
    response.content_length(body.size());
  } else {
    response.body() = {body.data(), body.size()};
    response.prepare_payload();
  }
  return response;
}

}  // namespace pms::server
