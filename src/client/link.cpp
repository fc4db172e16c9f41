// The client's TCP transport: link_core.h over a plain socket, whose bytes are the protocol's frames, and
// what every Link does on the caller's threads.
#include "client/link_core.h"

namespace pms::client {

namespace link_core {

template <>
struct StreamOps<tcp::socket> {
  static tcp::socket& socket(tcp::socket& s) { return s; }
  template <class Done>
  static void handshake(tcp::socket&, const std::string&, const std::string&, uint32_t, Done done) {
    done(error_code());
  }
  template <class Buffer, class Done>
  static void write_some(tcp::socket& s, const Buffer& buffer, Done done) {
    s.async_write_some(buffer, std::move(done));
  }
  static bool closed_by_peer(const error_code& ec) { return ec == asio::error::eof; }
};

}  // namespace link_core

namespace {

LinkOptions queue_options(size_t max_queued_bytes, uint32_t max_message) {
  LinkOptions options;
  options.max_queued_bytes = max_queued_bytes;
  options.max_message = max_message;
  return options;
}

}  // namespace

Link::Link(std::unique_ptr<Core> core, const std::string& host, uint16_t port, const std::string& path,
           const std::string& what)
    : core_(std::move(core)) {
  Core& c = *core_;
  boost::asio::post(c.io, [&c, host, port, path] { c.connect(host, std::to_string(port), path); });
  c.thread = std::thread([&c] { c.io.run(); });
  if (const std::string why = c.wait_open(); !why.empty()) throw ConnectionError(what + ": cannot connect: " + why);
}

Link::Link(const std::string& host, uint16_t port, const LinkOptions& options)
    : Link(std::make_unique<link_core::LinkCore<boost::asio::ip::tcp::socket>>(options), host, port, "",
           host + ":" + std::to_string(port)) {}

Link::Link(const std::string& host, uint16_t port, size_t max_queued_bytes, uint32_t max_message)
    : Link(host, port, queue_options(max_queued_bytes, max_message)) {}

Link::~Link() { close(); }

void Link::close() { core_->stop(); }

void Link::send(const std::vector<uint8_t>& frame) {
  Core& core = *core_;
  {
    std::lock_guard<std::mutex> lock(core.mutex);
    const size_t limit = core.options.max_send_queue_bytes;
    if (core.send_queued_bytes > 0 && core.send_queued_bytes + frame.size() > limit)
      core.lose("send queue over " + std::to_string(limit) + " bytes: the server is not reading");
    if (core.gone) core.throw_lost();
    core.send_queued_bytes += frame.size();
    core.counters.bytes_up += frame.size();
    core.counters.frames_up++;
  }
  boost::asio::post(core.io, [&core, frame]() mutable { core.enqueue(std::move(frame)); });
}

std::optional<protocol::Frame> Link::receive(std::chrono::milliseconds timeout) {
  Core& core = *core_;
  std::unique_lock<std::mutex> lock(core.mutex);
  if (!core.changed.wait_for(lock, timeout, [&] { return !core.queue.empty() || core.gone; })) return std::nullopt;
  if (core.queue.empty()) core.throw_lost();
  protocol::Frame frame = std::move(core.queue.front());
  core.queue.pop_front();
  core.queued_bytes -= frame.payload.size();
  if (core.read_paused && core.queued_bytes <= core.options.max_queued_bytes) {
    core.read_paused = false;
    boost::asio::post(core.io, [&core] { core.read(); });
  }
  return frame;
}

LinkCounters Link::counters() const {
  std::lock_guard<std::mutex> lock(core_->mutex);
  return core_->counters;
}

}  // namespace pms::client
