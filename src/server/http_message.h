// Between Beast's HTTP parser and the routes (http_routes.h): the parser's bounds, the answer to a
// request Beast could not parse, and an answer's status line and headers. Beast is slow to compile: only
// this file's .cpp, http_connection.cpp, http_server.cpp and the fuzz targets include this header
// (docs/architecture.md, "Stack").
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/catalogue.h"
#include "server/http_routes.h"
#include "server/limits.h"

namespace pms::server {

class StaticSite;

namespace http = boost::beast::http;
using HttpParser = http::request_parser<http::vector_body<uint8_t>>;

// A parser bounded by the limits (request line and headers, body).
void bound_parser(HttpParser& parser, const HttpLimits& limits);

// The 4xx for a request the parser refused. `buffered` is what the parser had not taken yet: with the
// parser's state it tells a request line over the header limit (414) from header fields over it (431).
HttpAnswer parse_error_answer(const boost::beast::error_code& ec, const HttpParser& parser, std::string_view buffered,
                              const HttpLimits& limits);

// A request refused on its header alone, before any byte of its body is read, and whether its connection
// must close after the answer.
struct HeaderRefusal {
  HttpAnswer answer;
  bool close = true;
};

// The refusal of a request whose header breaks RFC 9112's framing or Host rules or asks for an expectation
// the server does not meet; nothing for one the server answers. The parser's header must be done.
std::optional<HeaderRefusal> refuse_header(const HttpParser& parser);

// Whether the client waits for "100 Continue" before it sends the body (RFC 9110 §10.1.1): an HTTP/1.1
// request with a body and "Expect: 100-continue". The parser's header must be done.
bool expects_continue(const HttpParser& parser);

// The answer to a parsed request: the API's routes (with HEAD answered as GET) for /models and below,
// the page's files (when `site` is given) for every other path.
HttpAnswer answer_request(const Catalogue& catalogue, const HttpLimits& limits, PhaseTimes* phases,
                          const http::request<http::vector_body<uint8_t>>& request, StaticSite* site = nullptr);

// Whether `target` is the API's (/models and below, and any target that is not a path): those keep
// the routes' answers, whatever files the page holds.
bool is_api_target(std::string_view target);

// The status line and headers of `answer` (the same for GET and HEAD), replacing `out`'s text: only what
// a cache needs (docs/protocol.md, "Receiver-driven over HTTP"), so they depend only on the answer and
// keep_alive, never on the client or the time. `version` is the request's (10 or 11).
void write_response_head(const HttpAnswer& answer, bool keep_alive, unsigned version, std::string& out);

}  // namespace pms::server
