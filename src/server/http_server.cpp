// The HTTP transport's acceptor: connections take the I/O threads in turn (http_connection.h serves
// each), at most max_connections at once and max_connections_per_address from one client address; the
// others are answered 503 with Retry-After and closed.
#include "server/http_server.h"

#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include <cstdio>
#include <mutex>
#include <thread>

#include "common/error.h"
#include "server/http_connection.h"
#include "server/http_message.h"
#include "server/http_routes.h"
#include "server/io_threads.h"
#include "server/ws_connection.h"

namespace pms::server {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;
using std::chrono::milliseconds;

void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: http: %s\n", line.c_str()); }

// The answer to a connection over a limit, written once without waiting: it fits any socket buffer.
std::string refusal_text(const std::string& why) {
  const HttpAnswer answer = error_answer(503, why + "; try again later");
  std::string head;
  write_response_head(answer, false, 11, head);
  const std::span<const uint8_t> body = answer.body();
  return head + std::string(body.begin(), body.end());
}

void refuse(tcp::socket& socket, const std::string& text) {
  boost::system::error_code ignored;
  socket.non_blocking(true, ignored);
  socket.write_some(asio::buffer(text), ignored);
  socket.shutdown(tcp::socket::shutdown_both, ignored);
  socket.close(ignored);
}

}  // namespace

struct HttpServer::Impl {
  Impl(std::shared_ptr<CatalogueSlot> c, const HttpLimits& l, const WebOptions& w)
      : catalogues(std::move(c)), limits(l), web(w), site(w.root, w.site), contexts(make_contexts(l.threads)) {
    for (const auto& io : contexts) work.push_back(asio::make_work_guard(*io));
  }

  // One thread each: asio skips the hand-offs between threads (concurrency hint 1).
  static std::vector<std::unique_ptr<asio::io_context>> make_contexts(unsigned threads) {
    std::vector<std::unique_ptr<asio::io_context>> contexts;
    for (unsigned i = 0; i < io_thread_count(threads); ++i) contexts.push_back(std::make_unique<asio::io_context>(1));
    return contexts;
  }

  // Connections take the threads in turn; a connection stays on its thread.
  void accept() {
    asio::io_context& io = *contexts[next_context++ % contexts.size()];
    acceptor.async_accept(io, [this](const boost::system::error_code& ec, tcp::socket socket) {
      if (ec == asio::error::operation_aborted) return;  // stopped
      if (ec) return accept_failed(ec);
      admit(std::move(socket));
      accept();
    });
  }

  // Out of descriptors, accepting again at once would fail again at once.
  void accept_failed(const boost::system::error_code& ec) {
    log_line("accept: " + ec.message() + "; retrying in 100 ms");
    backoff.expires_after(milliseconds(100));
    backoff.async_wait([this](const boost::system::error_code& wait_ec) {
      if (!wait_ec) accept();
    });
  }

  void admit(tcp::socket socket) {
    static const std::string server_full = refusal_text("the server is at its connection limit");
    static const std::string address_full = refusal_text("this address is at its connection limit");
    if (stats.connections_active.load() >= limits.max_connections) {
      stats.connections_refused++;
      return refuse(socket, server_full);
    }
    const ClientAddress peer = peer_address(socket);
    // A trusted proxy carries many clients' connections: only the total bounds it.
    if (!addresses.open(peer, !limits.trusted_proxies.contains(peer))) {
      stats.connections_refused_per_address++;
      return refuse(socket, address_full);
    }
    try {
      stats.connections_active++;  // the connection's destructor takes both back
      stats.connections_opened++;
      start_http_connection(std::move(socket), peer, shared);
    } catch (const std::exception& e) {
      stats.connections_active--;
      addresses.close(peer);
      log_line(std::string("accept: internal error: ") + e.what());
    }
  }

  std::shared_ptr<CatalogueSlot> catalogues;
  HttpLimits limits;
  WebOptions web;
  StaticSite site;
  HttpStats stats;
  AddressBudgets addresses{limits.max_connections_per_address, double(limits.address_budget)};
  WsShared ws{catalogues, web};
  HttpServerShared shared{*catalogues, limits, stats, addresses, this, &site, &ws};
  std::vector<std::thread> threads;
  std::mutex stop_mutex;
  bool stopped = false;
  size_t next_context = 0;
  // Last: destroyed first, with the connections their handlers still hold (they use the members above);
  // the acceptor and the backoff timer, on the first context, before the contexts.
  std::vector<std::unique_ptr<asio::io_context>> contexts;
  std::vector<asio::executor_work_guard<asio::io_context::executor_type>> work;
  tcp::acceptor acceptor{*contexts.front()};
  asio::steady_timer backoff{*contexts.front()};
};

HttpServer::HttpServer(std::shared_ptr<const Catalogue> catalogue, const HttpLimits& limits, const std::string& host,
                       uint16_t port, const WebOptions& web)
    : HttpServer(std::make_shared<CatalogueSlot>(std::move(catalogue)), limits, host, port, web) {}

HttpServer::HttpServer(std::shared_ptr<CatalogueSlot> catalogues, const HttpLimits& limits, const std::string& host,
                       uint16_t port, const WebOptions& web)
    : impl_(std::make_unique<Impl>(std::move(catalogues), limits, web)) {
  impl_->catalogues->get()->check_limits(web.sessions);
  listen_on(impl_->acceptor, host, port, "HTTP");
}

HttpServer::~HttpServer() { stop(); }

uint16_t HttpServer::port() const { return impl_->acceptor.local_endpoint().port(); }

void HttpServer::start() {
  impl_->accept();
  for (const auto& io : impl_->contexts) start_io_threads(*io, 1, impl_->threads, log_line);
}

// Connections hold no state worth a goodbye: the loops stop, and destroying them closes their sockets.
void HttpServer::stop() {
  {
    std::lock_guard<std::mutex> lock(impl_->stop_mutex);
    if (impl_->stopped) return;
    impl_->stopped = true;
  }
  // No table build may post to a loop once it is stopped and destroyed.
  impl_->catalogues->table_builds().forget_group(impl_.get());
  for (const auto& io : impl_->contexts) io->stop();
  for (std::thread& t : impl_->threads)
    if (t.joinable()) t.join();
}

const HttpStats& HttpServer::stats() const { return impl_->stats; }

const ServerStats& HttpServer::ws_sessions() const { return impl_->ws.sessions; }

const WsStats& HttpServer::ws_stats() const { return impl_->ws.stats; }

size_t HttpServer::tracked_addresses() const { return impl_->addresses.tracked(); }

}  // namespace pms::server
