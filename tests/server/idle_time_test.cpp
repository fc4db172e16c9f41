// Idle time in the sender-driven mode (kim-lee-kobbelt §9; docs/protocol.md, "AHEAD"): with it on, the client's
// mesh is still local refinement's at every settled view and the splits that came ahead are ones a later view
// made without asking; the server keeps to its budget, answers a VIEW before anything more goes ahead, and a
// client that asks ahead and never reads, or flips between AHEAD and VIEW, costs bounded work and memory.
// With it off (the default), lap 2 of a lock-step flight costs 0 bytes: Streaming.ClientMeshEqualsLocal...
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <vector>

#include "client/streaming_client.h"
#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "server/limits.h"
#include "server/session.h"
#include "frame_of.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using test::faces_by_id;
using test::local_faces;
using test::orbit_path;
using Server = test::LoopbackTcpServer;

constexpr float kTolerance = 1.0f;

const test::Fixture& terrain() { return test::terrain_fixture(30000, 7); }

using test::frame_of;

protocol::View view_at(const Camera& camera, uint32_t frame) { return protocol::View{camera, kTolerance, frame}; }

// An in-process session (no I/O) greeted with `version` and opened on the terrain, BASE and CODEC taken.
struct InProcess {
  explicit InProcess(const server::ServerLimits& l, uint16_t version = protocol::kProtocolVersion,
                     protocol::StreamMode mode = protocol::StreamMode::sender_driven)
      : limits(l), session(terrain().catalogue, limits) {
    session.receive(frame_of(protocol::encode(protocol::Hello{version, "idle-test"})));
    protocol::Open open{"terrain", {}, mode};
    session.receive(frame_of(protocol::encode(open)));
    session.outbox().clear();
  }
  void send(const std::vector<uint8_t>& bytes) { session.receive(frame_of(bytes)); }
  // Frames out, with what each VSPLITS was (ahead or an answer); ERROR codes.
  struct Out {
    std::vector<std::pair<bool, size_t>> batches;  // (ahead, bytes)
    std::vector<protocol::ErrorCode> errors;
  };
  Out drain() {
    Out out;
    for (auto& outbox = session.outbox(); !outbox.empty(); outbox.pop_front()) {
      const std::vector<uint8_t>& bytes = *outbox.front();
      const protocol::MessageType type = protocol::MessageType(bytes[4]);
      if (type == protocol::MessageType::vsplits)
        out.batches.push_back({(bytes[protocol::kFrameHeaderBytes + 4] & 2) != 0, bytes.size()});
      if (type == protocol::MessageType::error) {
        const protocol::ServerMessage m = protocol::decode_server_message(frame_of(bytes), nullptr);
        out.errors.push_back(std::get<protocol::ErrorMessage>(m).code);
      }
    }
    return out;
  }
  // Pumps as a fast reader, to the end of the work; every slice bounded.
  Out run() {
    Out all;
    for (int call = 0; call < 100000 && session.has_work(); ++call) {
      session.pump();
      EXPECT_LE(session.last_work(), uint64_t(limits.slice_work) + 3 * 64);
      Out some = drain();
      all.batches.insert(all.batches.end(), some.batches.begin(), some.batches.end());
      all.errors.insert(all.errors.end(), some.errors.begin(), some.errors.end());
    }
    EXPECT_FALSE(session.has_work());
    return all;
  }

  server::ServerLimits limits;
  server::Session session;
};

uint64_t ahead_bytes(const InProcess::Out& out) {
  uint64_t bytes = 0;
  for (const auto& [ahead, size] : out.batches) bytes += ahead ? size : 0;
  return bytes;
}

TEST(IdleTime, MeshEqualsLocalRefinementAtEverySettledViewAndTheAheadSplitsGetUsed) {
  const test::Fixture& f = terrain();
  Server server(f.catalogue);
  client::ClientOptions options{kTolerance};
  options.ahead_frames = 3;
  client::StreamingClient client("127.0.0.1", server.tcp.port(), options, "terrain");
  // Small steps, each frame's VIEW answered before the next (settling): the frames whose view the held
  // hierarchy already satisfies are idle, and ask ahead.
  const std::vector<Camera> path = orbit_path(f.hierarchy, 160, 0.3f);
  uint32_t checked = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    client.frame_free_running(path[i]);
    client.settle_free_running(path[i]);
    if (i % 16 != 15) continue;
    ++checked;
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path[i], kTolerance))
        << "settled at frame " << i << ": the splits held ahead changed the mesh";
  }
  EXPECT_EQ(checked, 10u);
  EXPECT_GT(client.aheads_sent(), 0u) << "a satisfied view on a moving path is idle time";
  EXPECT_GT(client.ahead_splits(), 0u) << "the server streamed ahead";
  // The last view's mesh needs nothing it lacks: no request, whatever came ahead.
  const client::FrameReport last = client.frame_free_running(path.back());
  EXPECT_FALSE(last.requested);
  EXPECT_TRUE(last.satisfied);
}

TEST(IdleTime, AheadStaysWithinTheBudgetAndAViewGoesFirst) {
  const test::Fixture& f = terrain();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.3f);
  server::ServerLimits limits;
  limits.ahead_budget_bytes = 3000;
  InProcess s(limits);
  s.send(protocol::encode(view_at(path[0], 1)));
  const InProcess::Out answer = s.run();
  ASSERT_FALSE(answer.batches.empty());
  EXPECT_EQ(ahead_bytes(answer), 0u);

  // AHEAD of a view half an orbit on: much more than the budget wants sending.
  s.send(protocol::encode(protocol::Ahead{view_at(path[4], 1)}));
  ASSERT_TRUE(s.session.has_work());
  // One batch ahead, then a VIEW comes while it is still in the outbox: its answer is next, nothing ahead
  // goes out meanwhile.
  s.session.pump();
  ASSERT_EQ(s.session.outbox().size(), 1u);
  EXPECT_FALSE(s.session.has_work()) << "nothing more ahead while the outbox holds a batch";
  s.send(protocol::encode(view_at(path[1], 2)));
  InProcess::Out out = s.drain();
  ASSERT_EQ(out.batches.size(), 1u);
  EXPECT_TRUE(out.batches[0].first);
  const InProcess::Out rest = s.run();
  ASSERT_FALSE(rest.batches.empty());
  size_t first_ahead = rest.batches.size();
  for (size_t i = 0; i < rest.batches.size(); ++i)
    if (rest.batches[i].first) first_ahead = std::min(first_ahead, i);
  for (size_t i = first_ahead; i < rest.batches.size(); ++i) EXPECT_TRUE(rest.batches[i].first) << "batch " << i;
  EXPECT_GT(first_ahead, 0u) << "the VIEW's answer went first";

  // The budget: every batch ahead began below it, so the total is over it by at most the last batch.
  out.batches.insert(out.batches.end(), rest.batches.begin(), rest.batches.end());
  uint64_t sent = 0;
  size_t last = 0;
  for (const auto& [ahead, size] : out.batches) {
    if (!ahead) continue;
    EXPECT_LT(sent, limits.ahead_budget_bytes) << "a batch ahead began past the budget";
    sent += size;
    last = size;
  }
  EXPECT_GE(sent, limits.ahead_budget_bytes) << "the view ahead wanted more than the budget";
  EXPECT_LT(sent - last, limits.ahead_budget_bytes);
  // Spent: a later AHEAD gets nothing.
  s.send(protocol::encode(protocol::Ahead{view_at(path[6], 2)}));
  EXPECT_FALSE(s.session.has_work());
  EXPECT_EQ(ahead_bytes(s.run()), 0u);
}

TEST(IdleTime, AClientThatAsksAheadAndNeverReadsOrFlipsStaysBounded) {
  const test::Fixture& f = terrain();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 16, 0.3f);
  server::ServerLimits limits;
  limits.ahead_budget_bytes = 1u << 30;  // no budget to stop it: the outbox must
  // Never reads: whatever it sends, at most one batch ahead waits in the outbox.
  InProcess quiet(limits);
  for (size_t i = 0; i < path.size(); ++i) {
    quiet.send(protocol::encode(protocol::Ahead{view_at(path[i], uint32_t(i))}));
    for (int call = 0; call < 100 && quiet.session.has_work(); ++call) quiet.session.pump();
    EXPECT_FALSE(quiet.session.has_work()) << "AHEAD " << i << " keeps the session busy";
    EXPECT_LE(quiet.session.outbox().size(), 1u) << "AHEAD " << i;
  }
  // Flips: AHEAD and VIEW in turns, each pump bounded, every VIEW answered in full, memory that of its front.
  InProcess flipper(limits);
  size_t most_state = 0;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    flipper.send(protocol::encode(protocol::Ahead{view_at(path[i + 1], uint32_t(i))}));
    flipper.session.pump();
    flipper.send(protocol::encode(view_at(path[i], uint32_t(i))));
    const InProcess::Out out = flipper.run();
    EXPECT_TRUE(out.errors.empty());
    most_state = std::max(most_state, flipper.session.state_bytes() - flipper.session.front_bytes());
  }
  EXPECT_LT(most_state, size_t(64) << 10) << "beyond its front a session holds a few KB";
}

TEST(IdleTime, AheadIsRefusedWhereItHasNoMeaning) {
  const test::Fixture& f = terrain();
  const Camera camera = orbit_path(f.hierarchy, 4, 0.3f)[0];
  const std::vector<uint8_t> ahead = protocol::encode(protocol::Ahead{view_at(camera, 1)});
  // A session greeted with version 6 never asks ahead.
  InProcess v6(server::ServerLimits{}, protocol::kMinProtocolVersion);
  v6.send(ahead);
  EXPECT_EQ(v6.drain().errors, std::vector{protocol::ErrorCode::out_of_order});
  // The plain option makes every split it gets: nothing can wait for a view.
  InProcess plain(server::ServerLimits{}, protocol::kProtocolVersion, protocol::StreamMode::sender_plain);
  plain.send(ahead);
  EXPECT_EQ(plain.drain().errors, std::vector{protocol::ErrorCode::out_of_order});
  // A version the server does not speak.
  server::Session old(f.catalogue, server::ServerLimits{});
  old.receive(frame_of(protocol::encode(protocol::Hello{uint16_t(protocol::kMinProtocolVersion - 1), "old"})));
  const protocol::ServerMessage m = protocol::decode_server_message(frame_of(*old.outbox().back()), nullptr);
  EXPECT_EQ(std::get<protocol::ErrorMessage>(m).code, protocol::ErrorCode::unsupported_version);
}

}  // namespace
}  // namespace pms
