// Between Beast's HTTP parser and the routes (http_routes.h): the parser's bounds, the answer to a
// request Beast could not parse, and an answer's status line and headers. Beast is slow to compile: only
// this file's .cpp, http_server.cpp and the fuzz target include this header (docs/architecture.md, "Stack").
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "server/catalogue.h"
#include "server/http_routes.h"
#include "server/limits.h"

namespace pms::server {

namespace http = boost::beast::http;
using HttpParser = http::request_parser<http::vector_body<uint8_t>>;

// A parser bounded by the limits (request line and headers, body).
void bound_parser(HttpParser& parser, const HttpLimits& limits);

// The 4xx for a request the parser refused; `buffered` is what had arrived, to tell a URL that is too
// long (414) from too many headers (431).
HttpAnswer parse_error_answer(const boost::beast::error_code& ec, std::string_view buffered);

// The answer to a parsed request (the routes, with HEAD answered as GET).
HttpAnswer answer_request(const Catalogue& catalogue, const HttpLimits& limits,
                          const http::request<http::vector_body<uint8_t>>& request);

// The status line and headers of `answer` (the same for GET and HEAD), replacing `out`'s text: only what
// a cache needs (docs/protocol.md, "Receiver-driven over HTTP"), so they depend only on the answer and
// keep_alive, never on the client or the time. `version` is the request's (10 or 11).
void write_response_head(const HttpAnswer& answer, bool keep_alive, unsigned version, std::string& out);

}  // namespace pms::server
