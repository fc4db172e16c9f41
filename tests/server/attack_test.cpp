// Issue 14: hostile, slow and broken clients cannot hurt the server. Each test runs the real `pmstream serve
// --json` as a child process on loopback, flies a good client along a path once in quiet, then again while
// one kind of attacker works on the server from raw sockets, and asks of every attack the same: the good
// client ends with the mesh local refinement gives and its p99 latency stays within 3x of the quiet flight
// (asserted in the release build; a sanitizer build, which does not assert it, skips the quiet flight);
// within 3 s of the attack's end the server is back under 10 % of a core with every session slot free; SIGTERM
// ends it within 1 s with its totals. The deadlines are cut to a second (the idle timeout to three, ten under
// a sanitizer) so each attack meets them within the test.
//
// The p99 of 200 answers is their second slowest, and the virtual machines these tests run on stall a process
// a few times a minute: one stall in either flight moves the ratio far more than an attack does, with no
// attack at all. So a pair that misses the bound is
// flown twice more, quiet then attacked, and the bound holds when the median of the pairs' ratios is within
// it: an attack that really slows the server misses it in every pair.
#include <gtest/gtest.h>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <utility>

#include "attack_support.h"
#include "client/client_session.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "spm/hierarchy.h"
#include "spm/split_record.h"
#include "test_support.h"

namespace pms {
namespace {

using namespace test;
using protocol::ErrorCode;
using Errors = std::vector<ErrorCode>;

constexpr float kTolerance = 0.1f;
// A sanitizer build runs the flight much slower: a third of the path still lasts longer there than the whole
// path does in the release build, so every attack meets the same deadlines within the flight.
constexpr int kPathFrames = kSanitized ? 60 : 200;
constexpr uint32_t kMaxClientMessage = 4u << 20;  // the server's default, announced in HELLO_OK
const milliseconds kDeadline(1000);               // handshake, frame and write timeouts
// A client sends nothing while it applies an answer, and under a sanitizer applying the first one (tens of
// thousands of splits) took over 3 s on a loaded machine: the server rightly closed it as idle.
const milliseconds kIdleTimeout(kSanitized ? 10000 : 3000);
// Between the writes (or the connections) of an attack that goes on until the flight lands: still a flood, 200
// a second per attacker, but not also a contest for the two cores between the attackers' own threads, the
// good client and the server.
const milliseconds kPace(5);
constexpr double kMaxP99Ratio = 3;  // attacked / quiet

const Fixture& terrain() {
  return test::terrain_fixture(200000, 7);
}

// At 800 x 600 and a quarter pixel many answers take milliseconds rather than tenths of one, and the flight
// lasts seconds, long enough to meet every attack.
const std::vector<Camera>& good_path() {
  static const std::vector<Camera> path = [] {
    std::vector<Camera> cameras = orbit_path(terrain().hierarchy, kPathFrames, 0.3f);
    for (Camera& c : cameras) {
      c.width = 1280;
      c.height = 960;
    }
    return cameras;
  }();
  return path;
}

const Faces& good_mesh() {
  static const Faces faces = local_faces(terrain().snapped, good_path().back(), kTolerance);
  return faces;
}

// A close view whose answer is many times any socket buffer.
Camera close_view() { return orbit_path(terrain().hierarchy, 8, 2.4f).back(); }

std::vector<uint8_t> list_frame() { return protocol::encode(protocol::List{}); }

// A peer that has said HELLO and opened the terrain (and read both answers when `read_answers`).
std::unique_ptr<Peer> opened_peer(uint16_t port, int receive_buffer = 0, bool read_answers = true) {
  auto peer = std::make_unique<Peer>(port, receive_buffer);
  EXPECT_TRUE(peer->send(joined({hello_frame(), open_frame("terrain")}), after(kDeadline)));
  if (read_answers) {
    const auto hello_ok = peer->receive(after(milliseconds(3000)));
    const auto base = peer->receive(after(milliseconds(3000)));
    const auto codec = peer->receive(after(milliseconds(3000)));  // the terrain's packets are split records
    EXPECT_TRUE(hello_ok && hello_ok->type == protocol::MessageType::hello_ok);
    EXPECT_TRUE(base && base->type == protocol::MessageType::base);
    EXPECT_TRUE(codec && codec->type == protocol::MessageType::codec);
  }
  return peer;
}

class Attack : public ::testing::Test {
 protected:
  // The server with the short deadlines, and a quiet flight to measure the attacked one against. The
  // sender-driven tables are built before it listens: the attacks meet a server that is serving, and a
  // sanitizer build, which flies no quiet flight first, would otherwise spend the attack's first seconds
  // building them while every session waits (a cold start is table_builds_test's subject).
  void start(uint32_t max_sessions = 64) {
    server_ = std::make_unique<ServerProcess>(
        terrain().path, std::vector<std::string>{"--threads", "2", "--preload", "sender", "--max-sessions",
                                                 std::to_string(max_sessions),
                                                 "--handshake-timeout-ms", std::to_string(kDeadline.count()),
                                                 "--frame-timeout-ms", std::to_string(kDeadline.count()),
                                                 "--write-timeout-ms", std::to_string(kDeadline.count()),
                                                 "--idle-timeout-ms", std::to_string(kIdleTimeout.count()),
                                                 "--max-client-message", std::to_string(kMaxClientMessage)});
    good_mesh();  // built before any timing
    // Only the p99 bound reads the quiet flight, and a sanitizer build does not assert it: the attacked
    // flight's mesh and the sessions after it are checked in both builds.
    if (test::kSanitized) return;
    fly_quiet();
  }

  void fly_quiet() {
    const double cpu_before = server_->cpu_seconds();
    quiet_ = fly(port(), "terrain", good_path(), kTolerance);
    quiet_cpu_ = server_->cpu_seconds() - cpu_before;
    ASSERT_EQ(quiet_.mesh, good_mesh()) << "the quiet flight already differs from local refinement";
    ASSERT_EQ(server_->wait_for_sessions(0, milliseconds(3000)), 0u) << "the quiet flight's session lingers";
  }

  uint16_t port() const { return server_->port(); }
  bool landed() const { return landed_; }
  void ready() { ++ready_; }  // an attacker's attack is under way

  // `attacker(i)` on `attackers` threads while the good client flies the path again. An attack that takes
  // time to build up says ready() when it has, `wait_for_ready` times, before the flight starts (5 s at most).
  // An attacker keeps on until landed() (and finishes what it must then), every wait under a deadline.
  void fly_during(int attackers, const std::function<void(int)>& attacker, int wait_for_ready = 0) {
    attack_ = {attackers, attacker, wait_for_ready};
    landed_ = false;
    ready_ = 0;
    std::vector<std::thread> threads;
    for (int i = 0; i < attackers; ++i) threads.emplace_back(attacker, i);
    for (const Clock::time_point until = after(milliseconds(5000)); ready_ < wait_for_ready && Clock::now() < until;)
      std::this_thread::sleep_for(milliseconds(5));
    const double cpu_before = server_->cpu_seconds();
    try {
      attacked_ = fly(port(), "terrain", good_path(), kTolerance);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "the good client failed under attack: " << e.what();
    }
    attacked_cpu_ = server_->cpu_seconds() - cpu_before;
    landed_ = true;
    for (std::thread& t : threads) t.join();
    attack_end_ = Clock::now();
  }

  // What every attack must leave behind (issue 14's targets).
  void expect_unhurt(const char* attack) {
    const Clock::time_point deadline = attack_end_ + milliseconds(3000);
    EXPECT_EQ(attacked_.mesh, good_mesh()) << "the attacked flight does not end with local refinement's mesh";
    const double cpu = server_->wait_for_idle(0.10, remaining(deadline));
    EXPECT_LT(cpu, 0.10) << "server CPU (share of one core over a second) within 3 s of the attack's end";
    const uint64_t sessions = server_->wait_for_sessions(0, remaining(deadline));
    EXPECT_EQ(sessions, 0u) << "session slots still taken 3 s after the attack";
    auto p99_ratio = [&] { return percentile(attacked_.latency_ms, 99) / percentile(quiet_.latency_ms, 99); };
    std::vector<double> ratios;
    std::string pairs;  // the pairs before the last, which the line below reports
    if (!test::kSanitized) ratios.push_back(p99_ratio());
    if (!ratios.empty() && ratios[0] > kMaxP99Ratio) {
      for (int again = 0; again < 2; ++again) {
        const AttackRun run = attack_;
        const struct { std::vector<double> quiet, attacked; } previous{quiet_.latency_ms, attacked_.latency_ms};
        fly_quiet();
        fly_during(run.attackers, run.attacker, run.wait_for_ready);
        EXPECT_EQ(attacked_.mesh, good_mesh()) << "a flight flown again under attack differs from local refinement";
        pairs += "; before, p99 quiet " + format_ms(percentile(previous.quiet, 99)) + ", attacked " +
                 format_ms(percentile(previous.attacked, 99));
        ratios.push_back(p99_ratio());
        EXPECT_LT(server_->wait_for_idle(0.10, milliseconds(3000)), 0.10) << "server CPU after a flight flown again";
        EXPECT_EQ(server_->wait_for_sessions(0, milliseconds(3000)), 0u) << "sessions after a flight flown again";
      }
    }
    if (!ratios.empty()) {
      std::sort(ratios.begin(), ratios.end());
      EXPECT_LE(ratios[ratios.size() / 2], kMaxP99Ratio)
          << "median of the attacked / quiet p99 ratios over " << ratios.size() << " pairs of flights" << pairs;
    }
    const nlohmann::json stats = server_->stats();
    EXPECT_EQ(stats.at("sessions_failed").get<uint64_t>(), 0u) << "an attack caused an internal fault";
    const double quiet_p99 = percentile(quiet_.latency_ms, 99), attacked_p99 = percentile(attacked_.latency_ms, 99);
    const ServerProcess::Exit exit = server_->terminate(milliseconds(5000));
    EXPECT_TRUE(exit.exited) << "SIGTERM did not end the server in 5 s";
    EXPECT_LE(exit.seconds, 1.0) << "SIGTERM to exit";
    EXPECT_EQ(exit.exit_code, 0);
    EXPECT_TRUE(exit.stopped.has_value()) << "no \"stopped\" line with the totals";
    std::printf(
        "[ attack   ] %s: p99 quiet %.1f ms (p50 %.1f, %zu answers, %.1f s, server CPU %.2f s), attacked %.1f ms "
        "(p50 %.1f, %zu, %.1f s, server CPU %.2f s); CPU after %.1f %%; sessions after %llu; SIGTERM %.3f s; "
        "timed out %llu, protocol errors %llu, refused %llu, longest turn %llu us%s%s\n",
        attack, quiet_p99, percentile(quiet_.latency_ms, 50), quiet_.latency_ms.size(), quiet_.seconds, quiet_cpu_,
        attacked_p99, percentile(attacked_.latency_ms, 50), attacked_.latency_ms.size(), attacked_.seconds,
        attacked_cpu_, 100 * cpu, (unsigned long long)sessions, exit.seconds,
        (unsigned long long)stats.at("sessions_timed_out").get<uint64_t>(),
        (unsigned long long)stats.at("protocol_errors").get<uint64_t>(),
        (unsigned long long)stats.at("sessions_refused").get<uint64_t>(),
        (unsigned long long)stats.value("longest_turn_us", uint64_t(0)),
        test::kSanitized ? " (sanitizer build: no quiet flight, the p99 bound is the release run's)" : "",
        pairs.c_str());
  }

  static milliseconds remaining(Clock::time_point deadline) {
    return std::max(milliseconds(100), std::chrono::duration_cast<milliseconds>(deadline - Clock::now()));
  }

  static std::string format_ms(double ms) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f ms", ms);
    return text;
  }

  struct AttackRun {
    int attackers = 0;
    std::function<void(int)> attacker;
    int wait_for_ready = 0;
  };

  std::unique_ptr<ServerProcess> server_;
  AttackRun attack_;  // what fly_during ran, to fly it again
  Flight quiet_, attacked_;
  double quiet_cpu_ = 0, attacked_cpu_ = 0;  // the server's CPU seconds during each flight
  std::atomic<bool> landed_{false};
  std::atomic<int> ready_{0};
  Clock::time_point attack_end_;
};

// ---- resume fronts -------------------------------------------------------------------------------------

// The preorder code cannot name a node twice or one inside another listed leaf (it is the front's shape),
// so what a hostile front can do is cover the wrong trees, list nodes the model lacks or be malformed.
// Each is followed by a VIEW of the whole terrain: a session left with a front that misses trees would find
// splits whose cut vertices have no active ancestor (the old server looped on them forever).
struct BadFront {
  const char* what;
  std::vector<uint8_t> open;
  std::optional<ErrorCode> expected;  // none: a good front, answered with BASE and then the VIEW's VSPLITS
};

std::vector<BadFront> bad_fronts() {
  const ModelData model = model_of(terrain().hierarchy);
  const uint32_t roots = model.root_count;
  int leaf_depth = 0;  // where tree 0's v_t line reaches a real leaf
  for (uint32_t n = model.find({0, 1}); !model.is_leaf(n); n = model.first_child[n]) ++leaf_depth;
  int max_depth = 0;
  for (size_t n = 0; n < model.node_count(); ++n) max_depth = std::max(max_depth, model.id(uint32_t(n)).depth());
  FrontCode cut(roots);  // the last tree's split chain runs into the end of the payload
  cut.leaves(roots - 1);
  do cut.bits.push_back(true);
  while (cut.bits.size() % 8 != 0);
  auto front = [](uint32_t trees) { return FrontCode(trees); };
  return {
      {"one tree of all", open_with_front("terrain", front(1).leaves(1)), ErrorCode::bad_id},
      {"all trees but the last", open_with_front("terrain", front(roots - 1).leaves(roots - 1)), ErrorCode::bad_id},
      {"too many trees", open_with_front("terrain", front(roots + 1).leaves(roots + 1)), ErrorCode::bad_id},
      {"a real leaf marked split", open_with_front("terrain", front(roots).chain(leaf_depth + 1).leaves(roots - 1)),
       ErrorCode::bad_id},
      {"leaves below the model's depth",
       open_with_front("terrain", front(roots).leaves(roots - 1).chain(std::min(max_depth + 8, 63))),
       ErrorCode::bad_id},
      {"a split at depth 63", open_with_front("terrain", front(roots).chain(64).leaves(roots - 1)), ErrorCode::bad_id},
      {"no trees", open_with_front("terrain", front(0)), ErrorCode::bad_message},
      {"more trees than bits", open_with_front("terrain", front(0xFFFFFFFFu).leaves(roots)), ErrorCode::bad_message},
      {"a code cut short", open_with_front("terrain", cut), ErrorCode::bad_message},
      {"a byte after the code", open_with_front("terrain", front(roots).leaves(roots), {0xFF}), ErrorCode::bad_message},
      {"every root, the one good front", open_with_front("terrain", front(roots).leaves(roots)), std::nullopt},
  };
}

// HELLO, the OPEN, a VIEW; then reads until the server closes. A good front must see its VIEW answered.
void resume_with(uint16_t port, const BadFront& front) {
  Peer peer(port);
  const std::vector<uint8_t> bytes =
      joined({hello_frame(), front.open, view_frame(good_path().front(), kTolerance, 1)});
  ASSERT_TRUE(peer.send(bytes, after(kDeadline))) << front.what;
  if (!front.expected) {
    const bool answered = peer.read_until(
        [](const protocol::Frame& frame) {
          return frame.type == protocol::MessageType::vsplits && (frame.payload[4] & 1);  // the flags byte: final
        },
        after(milliseconds(5000)));
    EXPECT_TRUE(answered) << front.what << ": the VIEW after a good resume got no final VSPLITS";
    EXPECT_TRUE(peer.errors().empty()) << front.what;
    return;
  }
  EXPECT_TRUE(peer.wait_closed(after(milliseconds(2000)))) << front.what << ": not closed within 2 s";
  EXPECT_EQ(peer.errors(), Errors{*front.expected}) << front.what;
}

TEST_F(Attack, ResumeFrontsOfTheWrongShapeGetAnErrorAndHangNothing) {
  start();
  const std::vector<BadFront> fronts = bad_fronts();
  std::atomic<int> rounds{0};
  fly_during(2, [&](int) {
    do {
      for (const BadFront& front : fronts) {
        resume_with(port(), front);
        std::this_thread::sleep_for(kPace);
      }
      ++rounds;
    } while (!landed() && !::testing::Test::HasFailure());
  });
  EXPECT_GE(rounds, 2);
  expect_unhurt("resume fronts");
}

// ---- clients that never read ---------------------------------------------------------------------------

TEST_F(Attack, ClientsThatNeverReadAreClosedByTheWriteTimeout) {
  start();
  const std::vector<Camera> views = orbit_path(terrain().hierarchy, 64, 1.7f);
  std::atomic<int> silent{0}, pushy{0};
  fly_during(
      4,
      [&](int i) {
        bool stalled = false;
        do {
          // A small window: the server's answer stalls after a few kilobytes.
          std::unique_ptr<Peer> peer = opened_peer(port(), 4096, false);
          ASSERT_TRUE(peer->send(view_frame(close_view(), 0.25f, 1), after(kDeadline)));
          if (!std::exchange(stalled, true)) ready();  // its first answer stalls within milliseconds
          if (i % 2 == 0) {
            // It says no more either. Once the server gives up on it, what it had sent still drains, then ends;
            // a server still holding the session would stream on, and close only at the idle timeout.
            std::this_thread::sleep_for(2 * kDeadline);
            EXPECT_TRUE(peer->wait_closed(after(milliseconds(800)))) << "a silent non-reader was not closed";
            ++silent;
          } else {
            // It keeps sending VIEWs, which must not count as activity: the server stops reading, and closes.
            const Clock::time_point deadline = after(milliseconds(10000));
            for (uint32_t frame = 2; Clock::now() < deadline; ++frame) {
              if (!peer->send(view_frame(views[frame % views.size()], 0.25f, frame), after(milliseconds(5000)))) break;
              std::this_thread::sleep_for(kPace);
            }
            EXPECT_TRUE(peer->closed()) << "a non-reader sending VIEWs was not closed";
            ++pushy;
          }
        } while (!landed());
      },
      4);
  const uint64_t timed_out = server_->stats().at("sessions_timed_out").get<uint64_t>();
  EXPECT_GE(timed_out, uint64_t(silent + pushy)) << "every non-reader ends by a deadline";
  expect_unhurt("never-read");
}

// ---- slow drip -----------------------------------------------------------------------------------------

constexpr milliseconds kDrip(200);

// How long after `start` the server closed the peer, which must have been told `timeout` first.
void expect_closed_by_a_deadline(Peer& peer, Clock::time_point start, const char* what) {
  EXPECT_TRUE(peer.wait_closed(after(milliseconds(3000)))) << what;
  const double seconds = seconds_since(start);
  EXPECT_GE(seconds, 0.95 * std::chrono::duration<double>(kDeadline).count()) << what << ": closed early";
  EXPECT_LE(seconds, 2.5) << what << ": closed late";
  EXPECT_EQ(peer.errors(), Errors{ErrorCode::timeout}) << what;
}

TEST_F(Attack, SlowDripClientsAreClosedByTheFrameAndHandshakeTimeouts) {
  start();
  std::atomic<int> drips{0};
  fly_during(3, [&](int i) {
    do {
      if (i == 0) {  // a VIEW one byte at a time: the frame timeout
        std::unique_ptr<Peer> peer = opened_peer(port());
        const Clock::time_point start = Clock::now();
        EXPECT_FALSE(peer->drip(view_frame(close_view(), kTolerance, 1), kDrip)) << "the whole VIEW got in";
        expect_closed_by_a_deadline(*peer, start, "VIEW dripped");
      } else if (i == 1) {  // HELLO one byte at a time: the handshake (or frame) timeout
        const Clock::time_point start = Clock::now();
        Peer peer(port());
        EXPECT_FALSE(peer.drip(hello_frame(), kDrip)) << "the whole HELLO got in";
        expect_closed_by_a_deadline(peer, start, "HELLO dripped");
      } else {  // whole LISTs, read and answered, but never an OPEN: only the handshake timeout can end it
        const Clock::time_point start = Clock::now();
        Peer peer(port());
        EXPECT_TRUE(peer.send(hello_frame(), after(kDeadline)));
        for (Clock::time_point next = start + kDrip; !peer.closed() && seconds_since(start) < 3; next += kDrip) {
          if (!peer.send(list_frame(), after(kDeadline))) break;
          while (peer.receive(next)) {
          }  // its CATALOGUE, and in the end the ERROR
        }
        expect_closed_by_a_deadline(peer, start, "LIST without OPEN");
      }
      ++drips;
    } while (!landed());
  });
  EXPECT_GE(server_->stats().at("sessions_timed_out").get<uint64_t>(), uint64_t(drips.load()));
  expect_unhurt("slow drip");
}

// ---- idle connections ----------------------------------------------------------------------------------

// Connections that never say HELLO hold a slot each until the handshake timeout: past --max-sessions the
// rest are refused at once, and so is a good client; the timeout frees the slots, and the client gets in.
TEST_F(Attack, IdleSquattersAreRefusedAtOnceThenEvictedByTheHandshakeTimeout) {
  constexpr uint32_t kSlots = 64;
  constexpr int kSquatters = 300;
  start(kSlots);
  std::vector<std::unique_ptr<Peer>> squatters;
  const Clock::time_point connected_from = Clock::now();
  for (int i = 0; i < kSquatters; ++i) squatters.push_back(std::make_unique<Peer>(port()));
  {  // a client that says HELLO is refused too, at once (not when a squatter leaves)
    Peer late(port());
    EXPECT_TRUE(late.send(hello_frame(), after(kDeadline)));
    EXPECT_TRUE(late.wait_closed(after(milliseconds(500)))) << "a client over the limit was not closed at once";
    EXPECT_EQ(late.errors(), Errors{ErrorCode::server_full});
  }
  int refused = 0;
  for (auto& peer : squatters) {
    if (!peer->wait_closed(connected_from + milliseconds(500))) continue;
    EXPECT_EQ(peer->errors(), Errors{ErrorCode::server_full});
    ++refused;
  }
  EXPECT_EQ(refused, kSquatters - int(kSlots)) << "refused at once: all over the limit, and only those";
  for (auto& peer : squatters) {
    if (peer->closed()) continue;
    EXPECT_TRUE(peer->wait_closed(connected_from + kDeadline + milliseconds(2000))) << "a squatter outstayed";
    EXPECT_EQ(peer->errors(), Errors{ErrorCode::timeout});
  }
  EXPECT_EQ(server_->wait_for_sessions(0, milliseconds(2000)), 0u);
  fly_during(0, {});
  expect_unhurt("idle squatters");
}

// With room for them all, hundreds of idle connections (replaced as the server closes them) cost a flight
// nothing; every one is closed by the handshake timeout.
TEST_F(Attack, HundredsOfIdleConnectionsAreClosedByTheHandshakeTimeout) {
  constexpr int kIdle = 300;
  start(kIdle + 100);
  std::atomic<int> evicted{0};
  fly_during(
      1,
      [&](int) {
        struct Idle {
          std::unique_ptr<Peer> peer;
          Clock::time_point since;
        };
        std::vector<Idle> idle;
        for (int i = 0; i < kIdle; ++i) idle.push_back({std::make_unique<Peer>(port()), Clock::now()});
        ready();
        auto evict = [&](Idle& connection, Clock::time_point deadline) {
          if (!connection.peer->wait_closed(deadline)) return false;
          EXPECT_GE(seconds_since(connection.since), 0.95)
              << "an idle connection was closed before the handshake timeout";
          EXPECT_EQ(connection.peer->errors(), Errors{ErrorCode::timeout});
          ++evicted;
          return true;
        };
        while (!landed()) {
          for (Idle& connection : idle)
            if (evict(connection, Clock::now())) connection = {std::make_unique<Peer>(port()), Clock::now()};
          std::this_thread::sleep_for(milliseconds(50));
        }
        for (Idle& connection : idle)
          EXPECT_TRUE(evict(connection, connection.since + kDeadline + milliseconds(2000)))
              << "an idle connection outstayed";
      },
      1);
  EXPECT_GE(evicted, kIdle);
  EXPECT_EQ(server_->stats().at("sessions_refused").get<uint64_t>(), 0u);
  expect_unhurt("idle connections");
}

// ---- VIEW flood ----------------------------------------------------------------------------------------

// A client that sends thousands of VIEWs as fast as the socket takes them, reading all the while (the second
// one slowly, through a small window). Each VIEW replaces the last: the server must end with the last one's
// final batch, never send a split twice, and leave the client holding what that view needs.
void flood_views(uint16_t port, int index) {
  constexpr uint32_t kViews = 3000;
  const std::vector<Camera> views = orbit_path(terrain().hierarchy, kViews, 0.9f + float(index));
  std::vector<uint8_t> flood = joined({hello_frame(), open_frame("terrain")});
  for (uint32_t frame = 1; frame <= kViews; ++frame) append(flood, view_frame(views[frame - 1], kTolerance, frame));
  client::ClientSession session;
  session.adapt_options.tolerance = kTolerance;
  std::set<std::pair<uint32_t, uint64_t>> received;
  uint32_t last_batch = 0, last_final = 0, finals = 0;
  auto on_frame = [&](const protocol::Frame& frame) {
    if (frame.type == protocol::MessageType::base) session.on_base(protocol::decode_base(frame.payload));
    if (frame.type == protocol::MessageType::codec)
      session.on_codec(protocol::decode_codec(frame.payload, session.context()));
    if (frame.type != protocol::MessageType::vsplits) return;
    const protocol::VSplits batch = protocol::decode_vsplits(frame.payload, session.context());
    EXPECT_GE(batch.frame, last_batch) << "a batch for a VIEW older than one already answered";
    last_batch = batch.frame;
    for (const SplitRecord& split : batch.splits)
      EXPECT_TRUE(received.insert({split.vs.tree, split.vs.node}).second) << "a split sent twice";
    session.on_vsplits(batch);
    if (!batch.final) return;
    EXPECT_GT(batch.frame, last_final);
    last_final = batch.frame;
    ++finals;
  };
  Peer peer(port, index == 0 ? 0 : 4096);
  // What is asserted is the answer, not its speed: a sanitizer build, several times slower and beside the
  // other flights of the test on a shared machine, gets longer to send it.
  const Clock::time_point deadline = after(milliseconds(test::kSanitized ? 120000 : 30000));
  EXPECT_TRUE(peer.send_reading(flood, on_frame, deadline, milliseconds(index == 0 ? 0 : 10)));
  if (last_final < kViews)
    peer.read_until(
        [&](const protocol::Frame& frame) {
          on_frame(frame);
          return last_final == kViews;
        },
        deadline);
  EXPECT_EQ(last_final, kViews) << "flood " << index << ": the last VIEW's answer never ended";
  EXPECT_TRUE(peer.errors().empty());
  ASSERT_TRUE(session.has_model());
  session.refinement().set_view(session.view_params(views.back()));
  session.refinement().converge();
  EXPECT_TRUE(session.refinement().missing().empty()) << "the last view still wants splits it was not sent";
  EXPECT_EQ(faces_by_id(session.mesh()), local_faces(terrain().snapped, views.back(), kTolerance));
  std::printf("[ attack   ] VIEW flood %d: %u VIEWs, %u final answers, %zu splits\n", index, kViews, finals,
              received.size());
}

TEST_F(Attack, AViewFloodIsAnsweredOnlyForItsLatestView) {
  start();
  fly_during(2, [&](int i) { flood_views(port(), i); });
  expect_unhurt("VIEW flood");
}

// ---- LIST flood ----------------------------------------------------------------------------------------

TEST_F(Attack, AListFloodIsBoundedByBackPressureAndTheWriteTimeout) {
  start();
  const nlohmann::json before = server_->stats();
  std::atomic<uint64_t> unread_lists{0};
  fly_during(4, [&](int i) {
    // The server's default --max-message-rate: a session's messages beyond it wait, unread.
    constexpr size_t kRate = 500, kLists = 2000;
    if (i == 3) {  // one that reads every CATALOGUE: each LIST is answered, at the message rate
      std::unique_ptr<Peer> peer = opened_peer(port());
      size_t catalogues = 0;
      auto count = [&](const protocol::Frame& frame) { catalogues += frame.type == protocol::MessageType::catalogue; };
      const Clock::time_point started = Clock::now();
      const Clock::time_point deadline = after(milliseconds(1000 * kLists / kRate + 5000));
      EXPECT_TRUE(peer->send_reading(repeated(list_frame(), kLists), count, deadline));
      if (catalogues < kLists)
        peer->read_until(
            [&](const protocol::Frame& frame) {
              count(frame);
              return catalogues == kLists;
            },
            deadline);
      EXPECT_EQ(catalogues, kLists);
      // A burst of kRate (less HELLO and OPEN), then kRate a second.
      EXPECT_GE(seconds_since(started), 0.9 * double(kLists - kRate) / double(kRate)) << "faster than the rate";
      return;
    }
    const std::vector<uint8_t> lists = repeated(list_frame(), 1000);
    do {  // the rest never read, and send LISTs as long as the server takes them
      std::unique_ptr<Peer> peer = opened_peer(port(), 4096, false);
      const Clock::time_point start = Clock::now();
      while (seconds_since(start) < 10 && peer->send(lists, after(milliseconds(5000)))) {
        unread_lists += 1000;
        std::this_thread::sleep_for(kPace);
      }
      EXPECT_TRUE(peer->closed()) << "a LIST flooder that never reads was not closed";
    } while (!landed());
  });
  const nlohmann::json after_flood = server_->stats();
  const auto grew = [&](const char* field) {
    return double(after_flood.at(field).get<uint64_t>()) - double(before.at(field).get<uint64_t>());
  };
  EXPECT_LT(grew("peak_rss_bytes"), 50e6) << "the flood's peak memory";
  EXPECT_LT(grew("rss_bytes"), 50e6);
  std::printf("[ attack   ] LIST flood: %llu LISTs sent unread; peak RSS +%.1f MB, RSS +%.1f MB\n",
              (unsigned long long)unread_lists.load(), grew("peak_rss_bytes") / 1e6, grew("rss_bytes") / 1e6);
  expect_unhurt("LIST flood");
}

// ---- disconnects in mid-answer -------------------------------------------------------------------------

TEST_F(Attack, ClientsThatVanishMidAnswerLeaveNothingBehind) {
  start();
  std::atomic<int> vanished{0};
  fly_during(4, [&](int) {
    for (int round = 0; round < 25 || !landed(); ++round, std::this_thread::sleep_for(kPace)) {
      std::unique_ptr<Peer> peer = opened_peer(port(), 0, false);
      ASSERT_TRUE(peer->send(view_frame(close_view(), 0.25f, 1), after(kDeadline)));
      if (round % 3 != 0) {  // else gone before any answer
        const bool answering =
            peer->read_until([](const protocol::Frame& frame) { return frame.type == protocol::MessageType::vsplits; },
                             after(milliseconds(5000)));
        EXPECT_TRUE(answering) << "no VSPLITS for a close view";
      }
      if (round % 3 == 2) peer->abort();  // else closed with the answer unread
      peer.reset();
      ++vanished;
    }
  });
  EXPECT_GE(vanished, 100);
  expect_unhurt("disconnect mid-answer");
}

// ---- oversized, truncated and garbage frames -----------------------------------------------------------

// Sends `bytes` and expects the one ERROR `code` (any but internal when empty), then the close.
void expect_refused(uint16_t port, const std::vector<uint8_t>& bytes, std::optional<ErrorCode> code,
                    milliseconds within, const char* what) {
  Peer peer(port);
  peer.send(bytes, after(kDeadline));  // the server may close before taking it all
  EXPECT_TRUE(peer.wait_closed(after(within))) << what << ": not closed";
  ASSERT_EQ(peer.errors().size(), 1u) << what;
  if (code) {
    EXPECT_EQ(peer.errors()[0], *code) << what;
  } else {
    EXPECT_NE(peer.errors()[0], ErrorCode::internal) << what;
  }
}

TEST_F(Attack, OversizedTruncatedAndGarbageFramesEndOnlyTheirOwnSession) {
  start();
  std::atomic<int> frames{0};
  fly_during(3, [&](int i) {
    std::mt19937 random(uint32_t(i) + 14);
    const std::vector<uint8_t> hello_then =
        joined({hello_frame(), frame_header(kMaxClientMessage + 1, uint8_t(protocol::MessageType::view))});
    for (int round = 0; round < 10 || !landed(); ++round, ++frames, std::this_thread::sleep_for(kPace)) {
      if (i == 0) {  // over the limit, before and after HELLO: refused from the header alone
        expect_refused(port(), frame_header(0xFFFFFFFFu, 0x01), ErrorCode::too_large, kDeadline, "4 GiB HELLO");
        expect_refused(port(), hello_then, ErrorCode::too_large, kDeadline, "a VIEW one byte over the limit");
      } else if (i == 1) {  // noise: a random stream, or a frame of random type and payload
        std::vector<uint8_t> noise(1 + random() % 200);
        for (uint8_t& byte : noise) byte = uint8_t(random());
        if (round % 2) noise = joined({frame_header(uint32_t(noise.size()), uint8_t(random())), noise});
        expect_refused(port(), noise, std::nullopt, kDeadline + milliseconds(1500), "garbage");
      } else {  // half a VIEW, then gone (the slot must come back) or silent (the frame timeout)
        std::unique_ptr<Peer> peer = opened_peer(port());
        const std::vector<uint8_t> view = view_frame(close_view(), kTolerance, 1);
        ASSERT_TRUE(peer->send(std::span(view).first(view.size() / 2), after(kDeadline)));
        if (round % 2) {
          if (round % 4 == 1) peer->abort();
          continue;
        }
        expect_closed_by_a_deadline(*peer, Clock::now(), "half a VIEW");
      }
    }
  });
  EXPECT_GE(frames, 30);
  expect_unhurt("bad frames");
}

}  // namespace
}  // namespace pms
