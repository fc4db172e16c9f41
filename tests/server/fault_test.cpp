// Faults stay in their session: an allocation that fails while one session is handled ends that session
// with ERROR internal, and the server and every other session go on. The failure is injected through this
// test binary's operator new, armed for allocations of at least a given size (only the hostile session
// asks for blocks that large).
#include <gtest/gtest.h>

#include <utility>  // before asio with C++20

#include <boost/asio.hpp>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <thread>

#include "build/build.h"
#include "client/client.h"
#include "io/shapes.h"
#include "server/server.h"
#include "test_support.h"

namespace {

std::atomic<size_t> fail_from{SIZE_MAX};  // allocations of this many bytes or more throw bad_alloc
std::atomic<int> failures{0};

void* allocate(size_t size) {
  if (size >= fail_from.load(std::memory_order_relaxed)) {
    failures++;
    throw std::bad_alloc();
  }
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(size_t size) { return allocate(size); }
void* operator new[](size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace pms {
namespace {

struct Armed {
  explicit Armed(size_t bytes) { fail_from = bytes; }
  ~Armed() { fail_from = SIZE_MAX; }
};

std::shared_ptr<const server::Catalogue> terrain_catalogue(Hierarchy& hierarchy) {
  BuildResult built = build_progressive_mesh(make_terrain(20000, 3), BuildOptions{});
  hierarchy = std::move(built.hierarchy);
  const std::string path = (test::temp_dir() / "terrain.pms").string();
  write_pms(path, hierarchy, built.stats);
  return server::Catalogue::open({path});
}

protocol::Frame frame_of(const std::vector<uint8_t>& bytes) {
  protocol::FrameReader reader;
  reader.feed(bytes.data(), bytes.size());
  protocol::Frame frame;
  reader.next(frame);
  return frame;
}

// A resume front of every leaf.
std::vector<uint8_t> big_open(const Hierarchy& h) {
  std::vector<VertexId> leaves;
  for (uint32_t n = 0; n < h.node_count(); ++n)
    if (h.is_leaf(n)) leaves.push_back(h.id(n));
  return protocol::encode(protocol::Open{"terrain", leaves});
}

TEST(Fault, AnAllocationFailureInsideASessionEndsItWithInternal) {
  Hierarchy h;
  const auto catalogue = terrain_catalogue(h);
  server::Session session(catalogue, server::ServerLimits{});
  session.receive(frame_of(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "test"})));
  session.receive(frame_of(big_open(h)));
  {
    const Armed armed(1024);  // the resume's scratch and tags cannot be had
    for (int i = 0; i < 1000 && session.has_work(); ++i) session.pump();
  }
  EXPECT_GT(failures.load(), 0);
  ASSERT_TRUE(session.error().has_value());
  EXPECT_EQ(*session.error(), protocol::ErrorCode::internal);
  EXPECT_TRUE(session.closing());
  const protocol::Frame last = frame_of(*session.outbox().back());
  EXPECT_EQ(protocol::decode_error(last.payload).code, protocol::ErrorCode::internal);
}

TEST(Fault, AnAllocationFailureOnTheWireEndsOnlyThatSession) {
  Hierarchy h;
  const auto catalogue = terrain_catalogue(h);
  server::ServerLimits limits;
  limits.threads = 1;  // the good session shares the thread the fault happens on
  server::TcpServer tcp(catalogue, limits, "127.0.0.1", 0);
  tcp.start();
  client::StreamingClient good("127.0.0.1", tcp.port(), client::ClientOptions{1.0f});
  good.open("terrain");

  // A 3 MiB message (under the 4 MiB limit): the server's buffer for it grows as its bytes arrive, and
  // past 1 MiB it cannot. Nothing else here asks for a block that large.
  std::vector<uint8_t> open(protocol::kFrameHeaderBytes + (3u << 20), 0);
  const uint32_t length = 3u << 20;
  std::memcpy(open.data(), &length, 4);
  open[4] = uint8_t(protocol::MessageType::open);
  std::optional<protocol::ErrorCode> code;
  {
    const Armed armed(1u << 20);
    namespace asio = boost::asio;
    asio::io_context io;
    asio::ip::tcp::socket socket(io);
    socket.connect({asio::ip::make_address("127.0.0.1"), tcp.port()});
    boost::system::error_code ec;
    asio::write(socket, asio::buffer(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"})), ec);
    asio::write(socket, asio::buffer(open), ec);
    protocol::FrameReader reader;
    std::array<uint8_t, 4096> buffer;
    for (;;) {
      const size_t n = socket.read_some(asio::buffer(buffer), ec);
      if (ec) break;
      reader.feed(buffer.data(), n);
      protocol::Frame frame;
      while (reader.next(frame))
        if (frame.type == protocol::MessageType::error) code = protocol::decode_error(frame.payload).code;
    }
  }
  EXPECT_GT(failures.load(), 0);
  EXPECT_EQ(code, protocol::ErrorCode::internal);
  // The other session and the server go on.
  Camera camera;
  for (int k = 0; k < 3; ++k) camera.target[k] = 0.5f * (h.bbox_min[k] + h.bbox_max[k]);
  std::copy_n(camera.target, 3, camera.eye);
  camera.eye[1] += h.bbox_max[0] - h.bbox_min[0];
  camera.eye[2] += 0.5f * (h.bbox_max[0] - h.bbox_min[0]);
  camera.width = 320;
  camera.height = 240;
  EXPECT_GT(good.frame(camera).vsplits, 0u);
  EXPECT_EQ(tcp.stats().sessions_failed.load(), 1u);
  client::StreamingClient later("127.0.0.1", tcp.port(), client::ClientOptions{1.0f});
  later.open("terrain");
}

}  // namespace
}  // namespace pms
