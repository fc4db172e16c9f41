// The WebSocket on the HTTP port (/ws): the upgrade from an HTTP connection, then a server::Session driven
// as a TCP connection drives one (session_connection.h), each binary message carrying one TCP-protocol
// frame unchanged, both ways (docs/protocol.md, "WebSocket"). Beast's websocket is slow to compile: only
// ws_connection.cpp includes it.
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include <atomic>
#include <memory>
#include <optional>

#include "server/catalogue.h"
#include "server/catalogue_slot.h"
#include "server/client_address.h"
#include "server/http_message.h"
#include "server/stats.h"
#include "server/web_options.h"

namespace pms::server {

struct HttpServerShared;

// What the WebSocket sessions of one HttpServer share.
struct WsShared {
  WsShared(std::shared_ptr<CatalogueSlot> c, const WebOptions& w) : catalogues(std::move(c)), web(w) {}
  std::shared_ptr<CatalogueSlot> catalogues;
  const WebOptions& web;
  ServerStats sessions;  // the sessions' counters, as the TCP server keeps its own
  WsStats stats;
  std::atomic<uint64_t> next_id{0};
};

// Whether `target` is the WebSocket's (/ws, any query ignored).
bool is_ws_target(std::string_view target);

// The refusal of an upgrade request (not an upgrade 426, an Origin not allowed 403, data sent before the
// 101 400, the sessions cap 503); nothing when it is taken, and then its session is counted until it ends.
// `buffered`: bytes the connection read after the request.
std::optional<HttpAnswer> refuse_upgrade(const http::request<http::vector_body<uint8_t>>& request, size_t buffered,
                                         WsShared& ws);

// Answers the upgrade (101) and serves the session on `socket`'s executor until it ends. `peer` is
// counted in shared.addresses and shared.stats.connections_active, as the HTTP connection was: the
// WebSocket takes its place, and gives both back when it ends. `client` pays for its work: the peer, or
// behind a trusted proxy the client its X-Forwarded-For names.
void start_ws_connection(boost::asio::ip::tcp::socket socket, const ClientAddress& peer, const ClientAddress& client,
                         HttpServerShared& shared, http::request<http::vector_body<uint8_t>> request);

}  // namespace pms::server
