// Faults stay in their session: an allocation that fails while one session is handled ends that session
// with ERROR internal, and the server and every other session go on. The failure is injected through this
// test binary's operator new, armed for allocations of at least a given size (only the hostile session
// asks for blocks that large).
#include <gtest/gtest.h>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <thread>

#include "builder/build.h"
#include "client/streaming_client.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "server/limits.h"
#include "server/session.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/vertex_id.h"
#include "streaming_fixture.h"
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
// The nothrow forms too (std::stable_sort's buffer uses them): every form this binary can pair must
// come from the same allocator, or a sanitizer sees new and free mismatch.
void* operator new(size_t size, const std::nothrow_t&) noexcept { return std::malloc(size ? size : 1); }
void* operator new[](size_t size, const std::nothrow_t&) noexcept { return std::malloc(size ? size : 1); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace pms {
namespace {

struct Armed {
  explicit Armed(size_t bytes) { fail_from = bytes; }
  ~Armed() { fail_from = SIZE_MAX; }
};

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
  const test::Fixture f = test::make_fixture(make_terrain(20000, 3), "terrain");
  const Hierarchy& h = f.hierarchy;
  server::Session session(f.catalogue, server::ServerLimits{});
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
  const test::Fixture f = test::make_fixture(make_terrain(20000, 3), "terrain");
  server::ServerLimits limits;
  limits.threads = 1;  // the good session shares the thread the fault happens on
  server::TcpServer tcp(f.catalogue, limits, "127.0.0.1", 0);
  tcp.start();
  client::StreamingClient good("127.0.0.1", tcp.port(), client::ClientOptions{1.0f});
  good.open("terrain");

  // A 3 MiB message (under the 4 MiB limit): the server's buffer for it grows as its bytes arrive, and
  // past 1 MiB it cannot. Nothing else here asks for a block that large.
  std::vector<uint8_t> open(protocol::kFrameHeaderBytes + (3u << 20), 0);
  const uint32_t length = 3u << 20;
  std::memcpy(open.data(), &length, 4);
  open[4] = uint8_t(protocol::MessageType::open);
  const std::vector<std::vector<uint8_t>> messages = {
      protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"}), std::move(open)};
  std::optional<protocol::ErrorCode> code;
  {
    const Armed armed(1u << 20);
    code = test::send_raw(tcp.port(), messages);
  }
  EXPECT_GT(failures.load(), 0);
  EXPECT_EQ(code, protocol::ErrorCode::internal);
  // The other session and the server go on.
  const Camera camera = test::orbit_path(f.hierarchy, 4, 0.0f).back();
  EXPECT_GT(good.frame(camera).vsplits, 0u);
  EXPECT_EQ(tcp.stats().sessions_failed.load(), 1u);
  client::StreamingClient later("127.0.0.1", tcp.port(), client::ClientOptions{1.0f});
  later.open("terrain");
}

}  // namespace
}  // namespace pms
