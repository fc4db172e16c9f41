// Beast's messages to and from the routes (http_message.h).
#include "server/http_message.h"
#include "protocol/url_segment.h"
#include "server/static_site.h"

#include <algorithm>
#include <string>

namespace pms::server {
namespace {

std::string_view view_of(boost::beast::string_view s) { return {s.data(), s.size()}; }

using RequestHeader = http::request_header<>;

// Whether the parser had the whole request line when it refused the request: it takes the line once it
// ends within the header limit (and then the fields overflowed the limit), else the line is in `buffered`,
// whole or not.
bool request_line_ended(const HttpParser& parser, std::string_view buffered, uint32_t header_limit) {
  if (!parser.get().method_string().empty()) return true;  // taken: the request has its method
  return buffered.substr(0, header_limit).find("\r\n") != std::string_view::npos;
}

std::string_view trimmed(std::string_view s) {
  const size_t first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// RFC 9110 §5.6.2.
bool is_token(std::string_view s) {
  return !s.empty() &&
         s.find_first_not_of("!#$%&'*+-.^_`|~0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz") ==
             std::string_view::npos;
}

// The members of a list field over all its lines, trimmed, empty ones left out (RFC 9110 §5.6.1).
std::vector<std::string_view> list_members(const RequestHeader& header, http::field name) {
  std::vector<std::string_view> members;
  for (auto [line, end] = header.equal_range(name); line != end; ++line) {
    std::string_view rest = view_of(line->value());
    while (!rest.empty()) {
      const size_t comma = std::min(rest.find(','), rest.size());
      if (const std::string_view member = trimmed(rest.substr(0, comma)); !member.empty()) members.push_back(member);
      rest.remove_prefix(std::min(comma + 1, rest.size()));
    }
  }
  return members;
}

bool iequals(std::string_view a, std::string_view b) {
  return boost::beast::iequals(boost::beast::string_view(a.data(), a.size()),
                               boost::beast::string_view(b.data(), b.size()));
}

std::optional<HeaderRefusal> refusal(int status, const std::string& text) {
  return HeaderRefusal{error_answer(status, text), true};
}

// RFC 9112 §3.2: one Host, and HTTP/1.1 must send it. Its value is uri-host [":" port] (RFC 3986 §3.2.2),
// checked for the bytes those may hold.
std::optional<HeaderRefusal> refuse_host(const RequestHeader& header) {
  const size_t hosts = header.count(http::field::host);
  if (hosts == 0 && header.version() >= 11) return refusal(400, "an HTTP/1.1 request needs a Host header");
  if (hosts > 1) return refusal(400, "a request has one Host header");
  constexpr std::string_view kHostBytes =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-._~!$&'()*+,;=:[]%";
  if (hosts == 1 && view_of(header[http::field::host]).find_first_not_of(kHostBytes) != std::string_view::npos)
    return refusal(400, "the Host header is not a host and port");
  return std::nullopt;
}

// RFC 9112 §6.1 and §6.3. The server decodes chunked and nothing else; a body whose end it would find
// elsewhere than the client (or a proxy before it) meant is a next request smuggled in, so any doubt about
// the framing is refused, before the body is read, and the connection closed.
std::optional<HeaderRefusal> refuse_transfer_encoding(const HttpParser& parser) {
  const RequestHeader& header = parser.get();
  if (header.count(http::field::transfer_encoding) == 0) return std::nullopt;
  if (header.version() < 11) return refusal(400, "Transfer-Encoding in an HTTP/1.0 request");
  if (header.count(http::field::content_length) != 0)
    return refusal(400, "a request has Transfer-Encoding or Content-Length, not both");
  size_t chunked = 0;
  for (const std::string_view coding : list_members(header, http::field::transfer_encoding)) {
    const std::string_view name = trimmed(coding.substr(0, coding.find(';')));
    if (!is_token(name)) return refusal(400, "the Transfer-Encoding is not a list of transfer codings");
    if (!iequals(name, "chunked") || name.size() != coding.size())  // parameters too: chunked has none
      return refusal(501, "transfer coding '" + std::string(coding) + "': the server decodes chunked only");
    ++chunked;
  }
  // Beast must find the same framing, or it would read the body as something else than was checked here.
  if (chunked != 1 || !parser.chunked()) return refusal(400, "a request's transfer coding is chunked, once");
  return std::nullopt;
}

// RFC 9110 §10.1.1: 100-continue is the one expectation defined; the server meets no other.
std::optional<HeaderRefusal> refuse_expectation(const RequestHeader& header) {
  for (const std::string_view member : list_members(header, http::field::expect))
    if (!iequals(member, "100-continue"))
      return refusal(417, "expectation '" + std::string(member) + "': the server meets 100-continue only");
  return std::nullopt;
}

std::string cache_control(const HttpAnswer& answer) {
  switch (answer.caching) {
    case Caching::immutable:
      return "max-age=31536000, immutable";
    case Caching::max_age:
      return "max-age=" + std::to_string(answer.max_age_s);
    case Caching::revalidate:
      return "no-cache";
    default:
      return "no-store";
  }
}

}  // namespace

void bound_parser(HttpParser& parser, const HttpLimits& limits) {
  parser.header_limit(limits.max_header_bytes);
  parser.body_limit(limits.max_body_bytes);
}

HttpAnswer parse_error_answer(const boost::beast::error_code& ec, const HttpParser& parser, std::string_view buffered,
                              const HttpLimits& limits) {
  if (ec == http::error::header_limit) {
    if (!request_line_ended(parser, buffered, limits.max_header_bytes))
      return error_answer(414, "the request line is over " + std::to_string(limits.max_header_bytes) + " bytes");
    return error_answer(431,
                        "the request's header fields are over " + std::to_string(limits.max_header_bytes) + " bytes");
  }
  if (ec == http::error::body_limit) return error_answer(413, "the request body is too large");
  return error_answer(400, "malformed HTTP request: " + ec.message());
}

std::optional<HeaderRefusal> refuse_header(const HttpParser& parser) {
  if (auto refused = refuse_transfer_encoding(parser)) return refused;
  if (auto refused = refuse_host(parser.get())) return refused;
  return refuse_expectation(parser.get());
}

bool expects_continue(const HttpParser& parser) {
  if (parser.get().version() < 11) return false;  // an HTTP/1.0 client does not wait (RFC 9110 §10.1.1)
  const bool body = parser.chunked() || parser.content_length().value_or(0) > 0;
  const std::vector<std::string_view> expectations = list_members(parser.get(), http::field::expect);
  return body && std::ranges::any_of(expectations, [](std::string_view e) { return iequals(e, "100-continue"); });
}

bool is_api_target(std::string_view target) {
  if (target.empty() || target.front() != '/') return true;  // the routes answer it 400
  // Any spelling of /models ("/%6Dodels") is the API's: the routes send it to the canonical URL.
  const std::optional<std::string> path = protocol::url_path_normalize(target.substr(0, target.find('?')));
  return !path || *path == "/models" || path->starts_with("/models/");
}

HttpAnswer answer_request(const Catalogue& catalogue, const HttpLimits& limits, PhaseTimes* phases,
                          const http::request<http::vector_body<uint8_t>>& request, StaticSite* site) {
  HttpRequest r;
  r.phases = phases;
  r.method = view_of(request.method_string());
  r.target = view_of(request.target());
  r.body = request.body();
  if (const auto it = request.find(http::field::if_none_match); it != request.end())
    r.if_none_match = view_of(it->value());
  // A URL over the bound is the routes' 414 wherever it points.
  if (site && !is_api_target(r.target) && r.target.size() <= limits.max_target_bytes) return site->answer(r);
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
  header("Cache-Control", cache_control(answer));
  if (!answer.allow.empty()) header("Allow", answer.allow);
  if (!answer.location.empty()) header("Location", answer.location);
  if (answer.status == 503) header("Retry-After", "1");
  // HTTP/1.1 keeps the connection and HTTP/1.0 closes it unless the header says otherwise (RFC 9112 §9.3).
  if (version >= 11 && !keep_alive) header("Connection", "close");
  if (version < 11 && keep_alive) header("Connection", "keep-alive");
  out.append("\r\n");
}

}  // namespace pms::server
