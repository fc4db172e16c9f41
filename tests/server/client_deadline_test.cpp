// The client's deadlines (issue 14, requirement 5) against raw Boost.Asio peers on loopback: a server that
// never takes the connection, never answers, stops reading, stops halfway through a frame or closes
// mid-answer is a ConnectionError with its reason within the deadline, never a hang; with reconnect
// attempts a stalled server still ends in one, in bounded time. HELLO and OPEN go out together, so a peer
// that answers only once it has both answers within the deadline. Deadlines here are short (300 ms) and
// every bound has two seconds of slack for a loaded machine.
#include <utility>  // before asio with C++20

#include <gtest/gtest.h>
#include <array>
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "builder/build.h"
#include "client/link.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "test_support.h"

namespace pms {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr milliseconds kDeadline{300};
constexpr milliseconds kSlack{2000};

// A raw loopback server: every connection it accepts goes to `serve` (on the peer's thread, blocking
// calls allowed) and then stays open, and unread past what `serve` read, until the peer is destroyed.
class RawPeer {
 public:
  using Serve = std::function<void(tcp::socket&)>;

  // A `receive_buffer` (bytes) is set before listen, so accepted sockets have a small fixed window and a
  // client writing to a peer that does not read stalls after a few KiB instead of megabytes.
  explicit RawPeer(Serve serve, uint16_t port = 0, int receive_buffer = 0) : acceptor_(io_), serve_(std::move(serve)) {
    acceptor_.open(tcp::v4());
    acceptor_.set_option(tcp::acceptor::reuse_address(true));
    if (receive_buffer > 0) acceptor_.set_option(asio::socket_base::receive_buffer_size(receive_buffer));
    acceptor_.bind({asio::ip::make_address("127.0.0.1"), port});
    acceptor_.listen();
    port_ = acceptor_.local_endpoint().port();
    accept();
    thread_ = std::thread([this] { io_.run(); });
  }
  ~RawPeer() {
    io_.stop();
    thread_.join();
  }
  uint16_t port() const { return port_; }

 private:
  void accept() {
    acceptor_.async_accept([this](const boost::system::error_code& ec, tcp::socket socket) {
      if (ec) return;
      sockets_.push_back(std::move(socket));
      try {
        serve_(sockets_.back());
      } catch (const std::exception&) {
        // The client went first; what it saw is the test's to check.
      }
      accept();
    });
  }

  asio::io_context io_;
  tcp::acceptor acceptor_;
  std::deque<tcp::socket> sockets_;
  Serve serve_;
  uint16_t port_ = 0;
  std::thread thread_;
};

void silent(tcp::socket&) {}

protocol::Frame read_frame(tcp::socket& socket) {
  protocol::FrameReader reader;
  protocol::Frame frame;
  std::array<uint8_t, 4096> buffer;
  while (!reader.next(frame)) reader.feed(buffer.data(), socket.read_some(asio::buffer(buffer)));
  return frame;
}

// Reads HELLO, answers HELLO_OK, and reads nothing more.
void greet_then_stop_reading(tcp::socket& socket) {
  read_frame(socket);
  asio::write(socket, asio::buffer(protocol::encode(protocol::HelloOk{})));
}

// A frame of `payload` zero bytes; these peers never decode what they get.
std::vector<uint8_t> filler_frame(uint32_t payload) {
  std::vector<uint8_t> frame(protocol::kFrameHeaderBytes + payload, 0);
  for (int k = 0; k < 4; ++k) frame[size_t(k)] = uint8_t(payload >> (8 * k));
  frame[4] = uint8_t(protocol::MessageType::view);
  return frame;
}

struct Outcome {
  std::string what;
  Clock::duration took{};
};

// Runs `f`, which must end in a ConnectionError; returns its text and how long it took to come.
template <class F>
Outcome connection_error_of(F&& f) {
  const Clock::time_point start = Clock::now();
  try {
    f();
  } catch (const client::ConnectionError& e) {
    return {e.what(), Clock::now() - start};
  }
  ADD_FAILURE() << "no ConnectionError";
  return {"", Clock::now() - start};
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

client::ClientOptions answer_within(milliseconds timeout) {
  client::ClientOptions options;
  options.answer_timeout = timeout;
  return options;
}

TEST(ClientDeadline, ASilentServerIsAConnectionErrorWithinTheAnswerTimeout) {
  RawPeer peer(silent);
  const Outcome o =
      connection_error_of([&] { client::StreamingClient("127.0.0.1", peer.port(), answer_within(kDeadline)); });
  EXPECT_EQ(o.what, "server: no answer within 300 ms");
  EXPECT_GE(o.took, kDeadline);
  EXPECT_LT(o.took, kDeadline + kSlack);
}

// Connections a listener never accepts, until its accept queue is full and the kernel drops the next SYN
// (Linux: a backlog of 0 queues one). Returns false if every handshake completed.
bool fill_accept_queue(asio::io_context& io, const tcp::endpoint& at, std::deque<tcp::socket>& fillers) {
  for (int i = 0; i < 16; ++i) {
    auto done = std::make_shared<bool>(false);
    fillers.emplace_back(io).async_connect(at, [done](const boost::system::error_code&) { *done = true; });
    io.restart();
    io.run_for(milliseconds(200));
    if (!*done) return true;
  }
  return false;
}

TEST(ClientDeadline, AServerThatNeverTakesTheConnectionIsGivenUpAtTheConnectTimeout) {
  asio::io_context io;
  tcp::acceptor listener(io);
  listener.open(tcp::v4());
  listener.bind({asio::ip::make_address("127.0.0.1"), 0});
  listener.listen(0);
  std::deque<tcp::socket> fillers;
  if (!fill_accept_queue(io, listener.local_endpoint(), fillers))
    GTEST_SKIP() << "this kernel completes every handshake on a full listener, so no connect stalls on loopback";
  const uint16_t port = listener.local_endpoint().port();
  client::ClientOptions options;
  options.connect_timeout = kDeadline;
  const Outcome o = connection_error_of([&] { client::StreamingClient("127.0.0.1", port, options); });
  EXPECT_EQ(o.what, "127.0.0.1:" + std::to_string(port) + ": cannot connect: no connection within 300 ms");
  EXPECT_GE(o.took, kDeadline);
  EXPECT_LT(o.took, kDeadline + kSlack);
}

TEST(ClientDeadline, AServerThatStopsReadingIsLostAfterTheWriteTimeout) {
  RawPeer peer(greet_then_stop_reading, 0, 4096);
  client::LinkOptions options;
  options.write_timeout = kDeadline;
  options.max_send_queue_bytes = 64u << 20;  // the write deadline is under test here, not the queue's bound
  client::Link link("127.0.0.1", peer.port(), options);
  link.send(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "deadline"}));
  const std::optional<protocol::Frame> answer = link.receive(std::chrono::seconds(5));
  ASSERT_TRUE(answer && answer->type == protocol::MessageType::hello_ok);
  // Far more than the socket buffers hold (the sender's grows to 4 MiB on loopback), handed over at once;
  // the writes stall while the frames are still being handed over, so the clock starts before.
  const Outcome o = connection_error_of([&] {
    for (int i = 0; i < 32; ++i) link.send(filler_frame(1u << 20));
    link.receive(std::chrono::seconds(30));
  });
  EXPECT_EQ(o.what, "server: connection lost: no write progress for 300 ms");
  EXPECT_GE(o.took, kDeadline);
  EXPECT_LT(o.took, kDeadline + kSlack);
  EXPECT_THROW(link.send(filler_frame(1)), client::ConnectionError) << "the next send knows it too";
}

TEST(ClientDeadline, TheSendQueueIsBounded) {
  RawPeer peer(silent, 0, 4096);
  client::LinkOptions options;
  options.max_send_queue_bytes = 1u << 20;
  client::Link link("127.0.0.1", peer.port(), options);
  const uint32_t frame = 256u << 10;
  uint64_t handed_over = 0;
  const Outcome o = connection_error_of([&] {
    while (handed_over < (256u << 20)) {
      link.send(filler_frame(frame));
      handed_over += frame;
    }
  });
  EXPECT_EQ(o.what, "server: connection lost: send queue over 1048576 bytes: the server is not reading");
  // The queue's bound plus what the kernel took before the peer's window closed.
  EXPECT_LT(handed_over, 32u << 20);
  EXPECT_THROW(link.receive(milliseconds(0)), client::ConnectionError);
}

TEST(ClientDeadline, AFrameThatStopsHalfwayIsLostAfterTheReadTimeout) {
  RawPeer peer([](tcp::socket& socket) {
    // A VSPLITS header announcing 1000 bytes, then 10 of them and silence.
    const std::vector<uint8_t> start = {0xE8, 0x03, 0, 0, 0x84, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    asio::write(socket, asio::buffer(start));
  });
  client::LinkOptions options;
  options.read_timeout = kDeadline;
  client::Link link("127.0.0.1", peer.port(), options);
  const Outcome o = connection_error_of([&] { link.receive(std::chrono::seconds(30)); });
  EXPECT_EQ(o.what, "server: connection lost: a frame stalled: not complete after 300 ms");
  EXPECT_LT(o.took, kDeadline + kSlack);
  EXPECT_EQ(link.counters().bytes_down, 15u);
}

TEST(ClientDeadline, AServerThatClosesMidAnswerIsAConnectionErrorWithTheReason) {
  RawPeer peer([](tcp::socket& socket) {
    read_frame(socket);
    const std::vector<uint8_t> answer = protocol::encode(protocol::HelloOk{});
    asio::write(socket, asio::buffer(answer.data(), answer.size() / 2));
    socket.close();
  });
  // The default 30 s answer timeout: the error must come from the close, not from a deadline.
  const Outcome o = connection_error_of([&] { client::StreamingClient("127.0.0.1", peer.port()); });
  EXPECT_EQ(o.what, "server: connection lost: the server closed the connection mid-frame");
  EXPECT_LT(o.took, kSlack);
}

// HELLO and OPEN go out together, so BASE comes one round trip after connecting: a peer that answers
// nothing before it has read both still gets both, and its answer comes back within the deadline.
TEST(ClientDeadline, HelloAndOpenArePipelined) {
  std::mutex mutex;
  std::vector<protocol::MessageType> read;  // by the peer, before it answers
  RawPeer peer([&](tcp::socket& socket) {
    protocol::FrameReader reader;  // one for both: they may come in one read
    protocol::Frame frame;
    std::array<uint8_t, 4096> buffer;
    for (int k = 0; k < 2; ++k) {
      while (!reader.next(frame)) reader.feed(buffer.data(), socket.read_some(asio::buffer(buffer)));
      const std::lock_guard lock(mutex);
      read.push_back(frame.type);
    }
    const protocol::ErrorMessage refusal{protocol::ErrorCode::unknown_model, "answered after HELLO and OPEN"};
    asio::write(socket, asio::buffer(protocol::encode(refusal)));
  });
  try {
    client::StreamingClient("127.0.0.1", peer.port(), answer_within(kDeadline), "terrain");
    ADD_FAILURE() << "no error";
  } catch (const client::ConnectionError& e) {
    ADD_FAILURE() << "the client waited for HELLO_OK before OPEN: " << e.what();
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "answered after HELLO and OPEN")) << e.what();
  }
  const std::lock_guard lock(mutex);
  EXPECT_EQ(read, (std::vector<protocol::MessageType>{protocol::MessageType::hello, protocol::MessageType::open}));
}

TEST(ClientDeadline, CloseDoesNotWaitForAServerThatStoppedReading) {
  RawPeer peer(silent, 0, 4096);
  client::LinkOptions options;
  options.write_timeout = std::chrono::minutes(10);
  options.max_send_queue_bytes = 64u << 20;
  client::Link link("127.0.0.1", peer.port(), options);
  for (int i = 0; i < 16; ++i) link.send(filler_frame(1u << 20));
  std::this_thread::sleep_for(milliseconds(100));  // the kernel's buffers fill and a write waits
  const Clock::time_point start = Clock::now();
  link.close();
  EXPECT_LT(Clock::now() - start, kSlack);
  const Outcome o = connection_error_of([&] { link.send(filler_frame(1)); });
  EXPECT_EQ(o.what, "server: connection lost: closed by the client");
}

// A small terrain on a real server: the session the reconnect test holds before its server stalls.
struct Served {
  Hierarchy hierarchy;
  std::shared_ptr<const server::Catalogue> catalogue;
};

Served small_terrain() {
  BuildResult built = build_progressive_mesh(make_terrain(8000, 3));
  const std::string path = (test::temp_dir() / "terrain.pms").string();
  write_pms(path, built.hierarchy, built.stats);
  return {std::move(built.hierarchy), server::Catalogue::open({path})};
}

// From above one corner of the bounding box: the base mesh is far too coarse for it at 1 px.
Camera close_view(const Hierarchy& h) {
  Camera c;
  for (int k = 0; k < 3; ++k) {
    c.target[k] = 0.5f * (h.bbox_min[k] + h.bbox_max[k]);
    c.eye[k] = h.bbox_max[k] + 0.2f * (h.bbox_max[k] - h.bbox_min[k]);
  }
  c.width = 320;
  c.height = 240;
  return c;
}

TEST(ClientDeadline, ReconnectingToAStalledServerEndsInAConnectionErrorInBoundedTime) {
  const Served terrain = small_terrain();
  auto server = std::make_unique<server::TcpServer>(terrain.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  server->start();
  const uint16_t port = server->port();
  client::ClientOptions options = answer_within(kDeadline);
  options.reconnect_attempts = 3;
  options.reconnect_delay = milliseconds(20);
  std::vector<std::string> reasons;
  options.on_reconnect = [&](const std::string& reason, uint32_t) { reasons.push_back(reason); };
  client::StreamingClient client("127.0.0.1", port, options);
  client.open("terrain");
  // The server goes, and on its port comes one that takes connections and never answers.
  server.reset();
  RawPeer stalled(silent, port);
  const Outcome o = connection_error_of([&] { client.frame(close_view(terrain.hierarchy)); });
  ASSERT_EQ(reasons.size(), 3u);
  EXPECT_TRUE(contains(reasons[0], "server: connection lost")) << reasons[0];
  EXPECT_EQ(reasons[1], "server: no answer within 300 ms");
  EXPECT_EQ(reasons[2], "server: no answer within 300 ms");
  EXPECT_EQ(o.what, "server: no answer within 300 ms");
  // Three waits for HELLO_OK and the back-off before each attempt (20, 40, 80 ms), nothing more.
  EXPECT_GE(o.took, 3 * kDeadline);
  EXPECT_LT(o.took, 3 * kDeadline + milliseconds(140) + kSlack);
}

}  // namespace
}  // namespace pms
