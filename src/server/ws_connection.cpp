// One WebSocket session (Beast's advanced server: the upgrade is one branch of the HTTP connection, the
// same socket, the same limits). Each binary message is one TCP-protocol frame: a message that holds less
// or more, a text message, a message in too many pieces or pings past the message rate end the session
// with an ERROR. The rest (turns, slices, outbox, rate, deadlines) is session_connection.h's. Frames go
// out one message at a time, each write awaited: the outbox stays the back-pressure it is over TCP.
#include "server/ws_connection.h"

#include <boost/beast/websocket.hpp>

#include "protocol/message_types.h"
#include "server/http_connection.h"
#include "server/session_connection.h"

namespace pms::server {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using asio::ip::tcp;
using protocol::ErrorCode;
using std::chrono::milliseconds;
using Request = http::request<http::vector_body<uint8_t>>;

// Bytes taken from a message per read.
constexpr size_t kReadChunk = 16384;
// Reads one message may take: a frame split into more pieces than this is a flood of tiny fragments
// (a whole frame of the largest size in reads of a TCP segment each stays well under it).
constexpr uint32_t kMaxPiecesPerMessage = 4096;

bool iequal(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

std::string_view field(const Request& request, http::field name) {
  const auto it = request.find(name);
  return it == request.end() ? std::string_view() : std::string_view(it->value().data(), it->value().size());
}

// A browser names the page's origin; a client that is no browser sends none, and is no cross-site risk:
// the check keeps other sites' pages from opening sessions with a visitor's browser.
bool origin_allowed(const Request& request, const WebOptions& web) {
  const auto it = request.find(http::field::origin);
  if (it == request.end()) return true;
  const std::string_view origin(it->value().data(), it->value().size());
  if (web.allowed_origins.empty()) return iequal(origin, "http://" + std::string(field(request, http::field::host)));
  return std::ranges::any_of(web.allowed_origins, [&](const std::string& allowed) { return iequal(origin, allowed); });
}

// The bytes a server's unmasked frame header takes before `payload` bytes (RFC 6455 §5.2).
size_t frame_header_bytes(size_t payload) { return payload < 126 ? 2 : payload < 65536 ? 4 : 10; }

class WsConnection : public SessionConnection {
 public:
  WsConnection(tcp::socket socket, const ClientAddress& peer, const ClientAddress& client, HttpServerShared& shared,
               uint64_t id)
      : SessionConnection(socket.get_executor(), shared.ws->catalogues->get(), shared.ws->web.sessions, shared.ws->sessions,
                          id, shared.group),
        ws_(std::move(socket)),
        close_timer_(ws_.get_executor()),
        shared_(shared),
        address_(peer),
        client_(client) {}

  ~WsConnection() override {
    shared_.addresses.close(address_);
    shared_.stats.connections_active--;
  }

  void accept(Request request) {
    request_ = std::move(request);
    ws_.binary(true);
    ws_.auto_fragment(false);
    ws_.read_message_max(uint64_t(limits_.max_client_message) + protocol::kFrameHeaderBytes);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& response) { response.set(http::field::server, "pmstream"); }));
    ws_.control_callback([this](websocket::frame_type kind, beast::string_view) { on_control(kind); });
    // The 101 is small, but a peer that pipelined requests and read no answer may not take it.
    close_timer_.expires_after(milliseconds(limits_.handshake_timeout_ms));
    close_timer_.async_wait([self = self()](const boost::system::error_code& ec) {
      if (!ec) self->drop(true);
    });
    ws_.async_accept(request_, [self = self()](const boost::system::error_code& ec) { self->on_accept(ec); });
  }

 private:
  std::shared_ptr<WsConnection> self() { return std::static_pointer_cast<WsConnection>(shared_from_this()); }
  tcp::socket& socket() override { return ws_.next_layer(); }

  void on_accept(const boost::system::error_code& ec) {
    close_timer_.cancel();
    request_ = {};
    if (ec) {  // Beast answered the bad upgrade itself (400)
      shared_.ws->stats.refused_malformed++;
      stats_.sessions_active--;
      return drop(false);
    }
    shared_.ws->stats.upgrades++;
    stats_.sessions_opened++;
    start();
  }

  // ---- reading ----

  void start_read() override {
    ws_.async_read_some(in_, kReadChunk, [self = self()](const boost::system::error_code& ec, size_t n) {
      self->on_read(ec, n);
    });
  }

  void on_read(const boost::system::error_code& ec, size_t n) {
    pending_.read = false;
    if (closed()) return;
    if (ec == websocket::error::message_too_big) shared_.ws->stats.messages_refused++;
    if (ec) return close();  // the peer closed or broke the WebSocket: Beast has answered what it must
    if (ws_.got_text()) return refuse("a text message: each binary message carries one frame");
    frames_in_message_ += take_bytes(static_cast<const uint8_t*>(in_.data().data()), n);
    in_.consume(in_.size());
    if (ws_.is_message_done()) {
      const bool one_frame = frames_in_message_ == 1 && !reader_.mid_frame();
      frames_in_message_ = pieces_ = 0;
      if (!one_frame && !reader_.failed()) return refuse("a WebSocket message must carry exactly one frame");
    } else if (++pieces_ > kMaxPiecesPerMessage) {
      return refuse("a message in more than " + std::to_string(kMaxPiecesPerMessage) + " pieces");
    }
    serve();
  }

  // Beast answers pings itself: each costs a message of the rate.
  void on_control(websocket::frame_type kind) {
    if (kind != websocket::frame_type::ping || limits_.max_message_rate == 0 || session_.closing()) return;
    const Clock::time_point now = Clock::now();
    if (now - window_start_ >= std::chrono::seconds(1)) {
      window_start_ = now;
      pings_ = 0;
    }
    if (++pings_ != limits_.max_message_rate + 1) return;
    // Inside Beast's read: the session's turn comes after it, not within it.
    shared_.ws->stats.messages_refused++;
    session_.abort_with(ErrorCode::bad_message, "pings past the message rate");
    asio::post(ws_.get_executor(), [self = self()] { self->serve(); });
  }

  void refuse(const std::string& why) {
    shared_.ws->stats.messages_refused++;
    session_.abort_with(ErrorCode::bad_message, why);
    serve();
  }

  // ---- writing ----

  bool sending() const override { return writing_; }

  // One message in flight at a time; the outbox keeps the rest, and its bytes count in the send queue.
  bool write_now() override {
    if (writing_) return true;
    auto& outbox = session_.outbox();
    if (outbox.empty()) return false;
    message_ = std::move(outbox.front());
    outbox.pop_front();
    writing_ = true;
    ws_.async_write(asio::buffer(*message_), [self = self()](const boost::system::error_code& ec, size_t n) {
      self->on_written(ec, n);
    });
    return true;
  }

  void on_written(const boost::system::error_code& ec, size_t n) {
    writing_ = false;
    message_.reset();
    pending_.writable = false;
    if (closed()) return;
    if (ec) return close();
    count_written(n, n + frame_header_bytes(n));
    serve();
  }

  // A message being written serves the session again when it is done (on_written).
  void wait_until_writable() override {}

  // ---- the end ----

  Clock::duration charge(double units) override {
    const Clock::duration wait = shared_.addresses.charge(client_, units, Clock::now());
    if (wait > Clock::duration::zero()) shared_.ws->stats.budget_waits++;
    return wait;
  }

  // A close frame, and the socket once the peer answers it or the drain time is over; a reset at once.
  void shut(bool reset) override {
    if (reset || !ws_.is_open()) return drop(reset);
    close_timer_.expires_after(milliseconds(std::min<uint32_t>(1000, limits_.write_timeout_ms)));
    close_timer_.async_wait([self = self()](const boost::system::error_code& ec) {
      if (!ec) self->drop(true);
    });
    ws_.async_close(websocket::close_code::normal, [self = self()](const boost::system::error_code&) {
      self->close_timer_.cancel();
      self->drop(false);
    });
  }

  void drop(bool reset) {
    boost::system::error_code ignored;
    tcp::socket& s = ws_.next_layer();
    if (!s.is_open()) return;
    if (reset) s.set_option(asio::socket_base::linger(true, 0), ignored);
    s.shutdown(tcp::socket::shutdown_both, ignored);
    s.close(ignored);
  }

  websocket::stream<tcp::socket> ws_;
  asio::steady_timer close_timer_;
  HttpServerShared& shared_;
  const ClientAddress address_;  // the peer, counted in the per-address connections
  const ClientAddress client_;   // whose budget pays: the peer, or behind a trusted proxy the client it names
  Request request_;  // the upgrade, until it is answered
  beast::flat_buffer in_;
  size_t frames_in_message_ = 0;
  uint32_t pieces_ = 0;
  Buffer message_;  // the frame being written
  bool writing_ = false;
  Clock::time_point window_start_{};
  uint32_t pings_ = 0;
};

// Counts the session unless the cap is reached, with no window between the look and the count.
bool take_session(WsShared& ws) {
  uint64_t active = ws.sessions.sessions_active.load();
  do {
    if (active >= ws.web.sessions.max_sessions) return false;
  } while (!ws.sessions.sessions_active.compare_exchange_weak(active, active + 1));
  return true;
}

}  // namespace

bool is_ws_target(std::string_view target) { return target.substr(0, target.find('?')) == "/ws"; }

std::optional<HttpAnswer> refuse_upgrade(const Request& request, size_t buffered, WsShared& ws) {
  const auto malformed = [&ws](int status, const std::string& why) {
    ws.stats.refused_malformed++;
    return error_answer(status, why);
  };
  if (request.method() != http::verb::get || request.version() < 11)
    return malformed(400, "the WebSocket is opened by an HTTP/1.1 GET");
  if (!iequal(field(request, http::field::upgrade), "websocket"))
    return malformed(426, "/ws is a WebSocket: send Upgrade: websocket (docs/protocol.md, \"WebSocket\")");
  if (buffered > 0) return malformed(400, "no data may follow the upgrade before its answer");
  if (!origin_allowed(request, ws.web)) {
    ws.stats.refused_origin++;
    return error_answer(403, "this origin may not open the WebSocket (serve --ws-allowed-origin)");
  }
  if (!take_session(ws)) {
    ws.stats.refused_full++;
    ws.sessions.sessions_refused++;
    return error_answer(503, "the server is at its WebSocket session limit; try again later");
  }
  return std::nullopt;
}

void start_ws_connection(tcp::socket socket, const ClientAddress& peer, const ClientAddress& client,
                         HttpServerShared& shared, Request request) {
  auto connection = std::make_shared<WsConnection>(std::move(socket), peer, client, shared, ++shared.ws->next_id);
  connection->accept(std::move(request));
}

}  // namespace pms::server
