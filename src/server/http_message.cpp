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
  if (const auto it = request.find(http::field::if_none_match); it != request.end())
    r.if_none_match = view_of(it->value());
  return route(catalogue, limits, r);
}

void write_response_head(const HttpAnswer& answer, bool keep_alive, unsigned version, std::string& out) {
  const auto header = [&out](std::string_view name, std::string_view value) {
    out.append(name).append(": ").append(value).append("\r\n");
  };
  const auto status = http::int_to_status(unsigned(answer.status));
  out.assign(version == 10 ? "HTTP/1.0 " : "HTTP/1.1 ");
  out.append(std::to_string(answer.status)).append(" ").append(view_of(http::obsolete_reason(status))).append("\r\n");
  if (answer.status != 304) {  // a 304 has neither (RFC 9110 §15.4.5): the cache keeps the 200's
    header("Content-Type", answer.content_type);
    header("Content-Length", std::to_string(answer.body().size()));
  }
  if (!answer.etag.empty()) header("ETag", answer.etag);
  // No "public": the server takes no Authorization, and max-age alone lets a shared cache store the
  // answer (RFC 9111 §3).
  header("Cache-Control", answer.cacheable ? "max-age=31536000, immutable" : "no-store");
  if (!answer.allow.empty()) header("Allow", answer.allow);
  if (answer.status == 503) header("Retry-After", "1");
  // HTTP/1.1 keeps the connection and HTTP/1.0 closes it unless the header says otherwise (RFC 9112 §9.3).
  if (version >= 11 && !keep_alive) header("Connection", "close");
  if (version < 11 && keep_alive) header("Connection", "keep-alive");
  out.append("\r\n");
}

}  // namespace pms::server
