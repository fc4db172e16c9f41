// One HTTP connection of the receiver-driven and multilevel modes (http_server.h accepts them): Beast's
// request parser over a non-blocking socket, every request answered by the routes, every peer hostile.
// docs/operating.md, "HTTP", lists the limits it keeps.
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include "server/catalogue.h"
#include "server/catalogue_slot.h"
#include "server/client_address.h"
#include "server/limits.h"
#include "server/static_site.h"
#include "server/stats.h"
#include "server/work_budget.h"

namespace pms::server {

struct WsShared;

// What the connections of one HttpServer share.
struct HttpServerShared {
  const CatalogueSlot& catalogues;  // each request is answered from the one in place when it is routed
  const HttpLimits& limits;
  HttpStats& stats;
  AddressBudgets& addresses;
  const void* group;  // the TableBuilds group of this server's connections
  StaticSite* site;   // the page's files
  WsShared* ws;       // the WebSocket's sessions
};

// The address a socket's peer has, as the per-address limits key it.
ClientAddress peer_address(const boost::asio::ip::tcp::socket& socket);

// Serves `socket` on its executor until the peer leaves or a deadline passes. `peer` is already counted
// in shared.addresses (open()); the connection closes it there when it ends.
void start_http_connection(boost::asio::ip::tcp::socket socket, const ClientAddress& peer, HttpServerShared& shared);

}  // namespace pms::server
