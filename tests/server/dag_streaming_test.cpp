// The DAG mode over loopback (StreamMode::dag, zheng-chan 2006 §4–5): after every frame the thin client's
// mesh is the server's cut of the DAG, whatever the traversal; BUDGET mode never exceeds the budget on any
// frame; the priority traversal with a large N reaches local refinement's mesh for the view; a session
// resumes from the client's mesh, also in the middle of an answer; hostile DAG_VIEW and resume messages get
// ERROR and the server goes on serving others.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "client/local_transport.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "dag/compact.h"
#include "dag/cut.h"
#include "dag/dag.h"
#include "dag/traversal.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "server/catalogue.h"
#include "server/dag_mode.h"
#include "server/limits.h"
#include "server/session.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using protocol::StreamMode;
using test::faces_by_id;
using test::Fixture;
using test::make_fixture;
using test::orbit_path;

const Fixture& terrain() {
  return test::terrain_fixture(30000, 7);
}

client::ClientOptions dag_options(DagTraversal traversal, uint64_t budget, uint32_t max_ops, float tolerance) {
  client::ClientOptions options{tolerance};
  options.mode = StreamMode::dag;
  options.dag.traversal = traversal;
  options.dag.management = budget ? DagMode::budget : DagMode::free;
  options.dag.budget = budget;
  options.dag.max_ops = max_ops;
  return options;
}

// The session's cut, frame by frame, of a client bound to it in this process.
const server::DagSessionMode& dag_mode(const server::Session& session) {
  return dynamic_cast<const server::DagSessionMode&>(*session.session_mode());
}
const server::DagSessionMode& dag_mode(const test::InProcess& p) { return dag_mode(*p.session); }
// The same as a dense cut (the session keeps the compact form between turns).
DagCut session_cut(const Fixture& f, const server::Session& session) {
  return dag_mode(session).cut().dense(f.catalogue->find(f.name)->tables->dag());
}
DagCut session_cut(const Fixture& f, const test::InProcess& p) { return session_cut(f, *p.session); }

test::InProcess in_process(const Fixture& f, const client::ClientOptions& options) {
  static const server::ServerLimits limits = [] {
    server::ServerLimits l;
    l.batch_splits = 64;  // several DAG_OPS per answer
    return l;
  }();
  return test::in_process(f, options, limits);
}

// The mesh of a cut, made from scratch with the model's own split records: every split node split, parents
// first (DAG indices are breadth-first), dependencies by SelectiveMesh's forced chain (attaching the record
// a chain needs when it asks).
test::Faces cut_faces(const ModelData& model, const DagCut& cut) {
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  const auto attach = [&](uint32_t slot) {
    if (hierarchy.is_leaf(slot)) hierarchy.add_split(split_record(model, model.find(hierarchy.id(slot))));
  };
  const Dag& dag = cut.dag();
  for (uint32_t n = 0; n < dag.size(); ++n) {
    if (!cut.is_split(n)) continue;
    const uint32_t slot = hierarchy.find(model.id(dag.model_node(n)));
    if (slot == kNone || !mesh.is_active(slot)) continue;  // split already, by a forced chain
    attach(slot);
    for (int tries = 0;; ++tries) {
      const VSplitResult r = mesh.vsplit(slot);
      if (r.done) break;
      if (r.needs == kNone || tries > 64) {
        ADD_FAILURE() << "node " << n << " does not split";
        break;
      }
      attach(r.needs);
    }
  }
  return faces_by_id(mesh);
}

void expect_client_is_the_cut(DagTraversal traversal, uint64_t budget, uint32_t max_ops) {
  const Fixture& f = terrain();
  const ModelData& model = f.catalogue->find(f.name)->model();
  test::InProcess p = in_process(f, dag_options(traversal, budget, max_ops, 1.0f));
  const std::vector<Camera> path = orbit_path(f.hierarchy, 24, 0.3f);
  uint64_t splits = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    const client::FrameReport report = p.client->frame(path[i]);
    splits += report.vsplits;
    const DagCut cut = session_cut(f, p);
    std::string why;
    ASSERT_TRUE(cut.check(&why)) << "frame " << i << ": " << why;
    ASSERT_EQ(p.client->session().mesh().face_count(), cut.triangles()) << "frame " << i;
    ASSERT_EQ(faces_by_id(p.client->session().mesh()), cut_faces(model, cut)) << "frame " << i;
    if (budget) {
      ASSERT_LE(cut.triangles(), budget) << "frame " << i;
    }
  }
  EXPECT_GT(splits, 0u);
}

TEST(DagStreaming, ClientMeshIsTheServersCutPriorityFree) { expect_client_is_the_cut(DagTraversal::priority, 0, 300); }
TEST(DagStreaming, ClientMeshIsTheServersCutLinearFree) { expect_client_is_the_cut(DagTraversal::linear, 0, 100); }
TEST(DagStreaming, ClientMeshIsTheServersCutConstantFree) {
  expect_client_is_the_cut(DagTraversal::constant_time, 0, 100);
}
TEST(DagStreaming, ClientMeshIsTheServersCutAndWithinBudgetEveryTraversal) {
  for (DagTraversal t : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time}) {
    SCOPED_TRACE(int(t));
    expect_client_is_the_cut(t, 3000, 200);
  }
}

// zheng-chan §4's management (--management auto): the client asks in FREE mode while its mesh plus the 2 N
// triangles an answer can add fits the budget, in BUDGET mode once it may not (and for the converged first
// answer); both happen along a path that closes in, the mesh is the server's cut and within the budget every
// frame, and it is the mesh of a client asking in BUDGET mode throughout (the server's BUDGET counts the
// cut's triangles, so in a frame the rule sends FREE the budget could not have stopped a split).
TEST(DagStreaming, ManagementAutoSwitchesToBudgetNearTheBudget) {
  const Fixture& f = terrain();
  const ModelData& model = f.catalogue->find(f.name)->model();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 24, 0.3f);
  constexpr uint32_t kN = 200;
  uint64_t most = 0;
  {
    test::InProcess free = in_process(f, dag_options(DagTraversal::priority, 0, kN, 1.0f));
    for (const Camera& c : path) most = std::max<uint64_t>(most, free.client->frame(c).faces);
  }
  const uint64_t budget = most * 4 / 5;
  client::ClientOptions automatic = dag_options(DagTraversal::priority, budget, kN, 1.0f);
  automatic.dag_management.automatic = true;
  test::InProcess p = in_process(f, automatic);
  test::InProcess fixed = in_process(f, dag_options(DagTraversal::priority, budget, kN, 1.0f));
  int free_frames = 0, budget_frames = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    const uint64_t before = p.client->session().mesh().face_count();
    p.client->frame(path[i]);
    fixed.client->frame(path[i]);
    const protocol::DagView& asked = p.client->last_dag_request();
    const bool free = i > 0 && before + 2 * kN <= budget;
    ASSERT_EQ(asked.management, free ? DagMode::free : DagMode::budget) << "frame " << i << ", " << before;
    ASSERT_EQ(asked.budget, free ? 0 : budget) << "frame " << i;
    (free ? free_frames : budget_frames) += 1;
    const DagCut cut = session_cut(f, p);
    std::string why;
    ASSERT_TRUE(cut.check(&why)) << "frame " << i << ": " << why;
    ASSERT_EQ(faces_by_id(p.client->session().mesh()), cut_faces(model, cut)) << "frame " << i;
    ASSERT_LE(cut.triangles(), budget) << "frame " << i;
    ASSERT_EQ(faces_by_id(p.client->session().mesh()), faces_by_id(fixed.client->session().mesh())) << "frame " << i;
  }
  EXPECT_GT(free_frames, 0);
  EXPECT_GT(budget_frames, 1) << "only the first answer asked in BUDGET mode: the budget never came near";
}

// zheng-chan §5: at convergence the priority traversal is the adaptation loop's mesh of the view.
TEST(DagStreaming, PriorityWithLargeNConvergesToLocalRefinement) {
  const Fixture& f = terrain();
  test::InProcess p = in_process(f, dag_options(DagTraversal::priority, 0, protocol::kMaxDagOps, 1.0f));
  const Camera camera = orbit_path(f.hierarchy, 8, 0.1f).back();
  int frames = 0;
  for (; frames < 50; ++frames) {
    const uint64_t before = p.client->session().mesh().face_count();
    const client::FrameReport report = p.client->frame(camera);
    if (report.vsplits == 0 && p.client->session().mesh().face_count() == before) break;
  }
  ASSERT_LT(frames, 50) << "no convergence";
  EXPECT_GT(frames, 0);
  EXPECT_GT(p.client->session().mesh().face_count(), f.catalogue->find(f.name)->tables->dag().base_faces())
      << "a view with detail";
  EXPECT_EQ(faces_by_id(p.client->session().mesh()), test::local_faces(f.snapped, camera, 1.0f));
}

// A session's first view is answered with its converged mesh, whatever traversal and N the client asked
// for (docs/internals.md, "The DAG mode"); the next views are N-limited again.
TEST(DagStreaming, FirstAnswerIsTheConvergedMesh) {
  const Fixture& f = terrain();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.1f);
  for (DagTraversal t : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time}) {
    SCOPED_TRACE(int(t));
    test::InProcess p = in_process(f, dag_options(t, 0, 50, 1.0f));
    const client::FrameReport first = p.client->frame(path.back());
    EXPECT_GT(first.vsplits, 50u);
    EXPECT_EQ(faces_by_id(p.client->session().mesh()), test::local_faces(f.snapped, path.back(), 1.0f));
    const client::FrameReport second = p.client->frame(path.front());
    if (t != DagTraversal::constant_time) {  // constant-time bounds evaluations, not operations
      EXPECT_LE(second.vsplits, 50u);
    }
    std::string why;
    EXPECT_TRUE(session_cut(f, p).check(&why)) << why;
  }
}

// Between answers a DAG session holds its cut's compact code (at most 2 bits per split node and one per root)
// and the mode itself: far below a byte per node.
TEST(DagStreaming, StateIsTheCompactCut) {
  const Fixture& f = terrain();
  test::InProcess p = in_process(f, dag_options(DagTraversal::priority, 0, 300, 1.0f));
  for (const Camera& c : orbit_path(f.hierarchy, 6, 0.0f)) p.client->frame(c);
  const CompactDagCut& cut = dag_mode(p).cut();
  const size_t nodes = f.catalogue->find(f.name)->tables->dag().size();
  const uint32_t roots = f.catalogue->find(f.name)->model().root_count;
  EXPECT_GT(cut.split_count(), 100u);
  EXPECT_LE(cut.code_bits(), 2 * uint64_t(cut.split_count()) + roots);
  EXPECT_LE(cut.memory_bytes(), cut.code_bits() / 8 + 8);
  EXPECT_EQ(dag_mode(p).state_bytes(), sizeof(server::DagSessionMode) + cut.memory_bytes());
  EXPECT_LT(dag_mode(p).state_bytes(), nodes / 10) << "issue 16: 10 % of a byte per node";
}

std::vector<uint8_t> dag_view_frame(uint32_t max_ops, uint8_t traversal, uint8_t management, uint64_t budget) {
  protocol::DagView good;
  std::vector<uint8_t> frame = protocol::encode(good);
  const size_t at = protocol::kFrameHeaderBytes + 56;  // after the view
  std::memcpy(&frame[at], &max_ops, 4);
  frame[at + 4] = traversal;
  frame[at + 5] = management;
  std::memcpy(&frame[at + 6], &budget, 8);
  return frame;
}

TEST(DagStreaming, HostileDagViewsGetErrorAndOthersAreServed) {
  const Fixture& f = terrain();
  server::TcpServer tcp(f.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  using protocol::ErrorCode;
  const auto hello = protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"});
  const auto open_dag = protocol::encode(protocol::Open{f.name, {}, StreamMode::dag});
  const auto open_sender = protocol::encode(protocol::Open{f.name, {}, StreamMode::sender_driven});
  const auto answer = [&](const std::vector<uint8_t>& open, const std::vector<uint8_t>& view) {
    return test::send_raw(tcp.port(), {hello, open, view});
  };
  EXPECT_EQ(answer(open_dag, dag_view_frame(300, 3, 0, 0)), ErrorCode::bad_message) << "bad traversal";
  EXPECT_EQ(answer(open_dag, dag_view_frame(0, 0, 0, 0)), ErrorCode::bad_message) << "N = 0";
  EXPECT_EQ(answer(open_dag, dag_view_frame(UINT32_MAX, 0, 0, 0)), ErrorCode::bad_message) << "huge N";
  EXPECT_EQ(answer(open_dag, dag_view_frame(300, 0, 1, UINT64_MAX)), ErrorCode::bad_message) << "absurd budget";
  EXPECT_EQ(answer(open_dag, dag_view_frame(300, 0, 1, 0)), ErrorCode::bad_message) << "budget mode, no budget";
  EXPECT_EQ(answer(open_dag, dag_view_frame(300, 0, 7, 0)), ErrorCode::bad_message) << "bad management";
  EXPECT_EQ(test::send_raw(tcp.port(), {hello, dag_view_frame(300, 0, 0, 0)}), ErrorCode::out_of_order)
      << "before OPEN";
  EXPECT_EQ(answer(open_sender, dag_view_frame(300, 0, 0, 0)), ErrorCode::out_of_order) << "in a sender session";
  EXPECT_EQ(answer(open_dag, protocol::encode(protocol::View{})), ErrorCode::out_of_order) << "VIEW in a DAG session";
  // The server goes on serving a good DAG session.
  client::StreamingClient good("127.0.0.1", tcp.port(), dag_options(DagTraversal::linear, 5000, 300, 1.0f));
  good.open(f.name);
  const client::FrameReport report = good.frame(orbit_path(f.hierarchy, 4, 0.2f).back());
  EXPECT_GT(report.vsplits, 0u);
  EXPECT_LE(report.faces, 5000u);
}

// The front of the mesh whose split nodes are v and its ancestors (every other tree at its root).
std::vector<VertexId> front_splitting(const ModelData& model, VertexId v) {
  std::vector<VertexId> front;
  for (uint32_t t = 0; t < model.root_count; ++t)
    if (t != v.tree) front.push_back({t, 1});
  for (int d = 0; d <= v.depth(); ++d)
    for (int k = 0; k < 2; ++k)
      if (const VertexId c = ancestor_at_depth(v, d).child(k); d == v.depth() || !is_ancestor_or_self(c, v))
        front.push_back(c);
  return front;
}

// A resume is the client's word about its mesh: a front over other trees, a leaf the model lacks, a mesh that
// is no cut of the DAG (a split without its dependency) and a front with bytes after it get ERROR; the server
// goes on serving a good DAG session, and the front of a real cut resumes.
TEST(DagStreaming, HostileResumesGetErrorAndOthersAreServed) {
  const Fixture& f = terrain();
  const ModelData& model = f.catalogue->find(f.name)->model();
  const Dag& dag = f.catalogue->find(f.name)->tables->dag();
  server::TcpServer tcp(f.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  using protocol::ErrorCode;
  const auto hello = protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"});
  const auto resume = [&](const std::vector<VertexId>& front) {
    return test::send_raw(tcp.port(), {hello, protocol::encode(protocol::Open{f.name, front, StreamMode::dag}),
                                       dag_view_frame(300, 0, 0, 0)});
  };
  EXPECT_EQ(resume({VertexId{0, 1}}), ErrorCode::bad_id) << "a front over one tree";
  uint32_t leaf = kNone, dependent = kNone;
  for (uint32_t n = 0; n < model.node_count() && leaf == kNone; ++n)
    if (model.is_leaf(n) && model.parent[n] != kNone) leaf = n;
  for (uint32_t n = 0; n < dag.size() && dependent == kNone; ++n)
    if (dag.parents(n).size() == 2) dependent = n;
  ASSERT_NE(leaf, kNone);
  ASSERT_NE(dependent, kNone) << "a DAG without dependency edges tests nothing here";
  EXPECT_EQ(resume(front_splitting(model, model.id(leaf))), ErrorCode::bad_id) << "a split of a model leaf";
  EXPECT_EQ(resume(front_splitting(model, model.id(dag.model_node(dependent)))), ErrorCode::bad_id)
      << "a split whose dependency is collapsed: no cut";
  std::vector<uint8_t> trailing =
      protocol::encode(protocol::Open{f.name, front_splitting(model, {0, 1}), StreamMode::dag});
  trailing.push_back(0);
  const uint32_t length = uint32_t(trailing.size() - protocol::kFrameHeaderBytes);
  std::memcpy(trailing.data(), &length, 4);
  EXPECT_EQ(test::send_raw(tcp.port(), {hello, trailing, dag_view_frame(300, 0, 0, 0)}), ErrorCode::bad_message)
      << "bytes after the front";
  // The front of a real cut (the closure of `dependent`, dependencies first) resumes: answered, no ERROR.
  DagCut cut(dag);
  std::vector<uint32_t> todo{dependent};
  while (!todo.empty()) {
    const uint32_t n = todo.back();
    if (cut.is_split(n)) {
      todo.pop_back();
      continue;
    }
    const uint32_t hp = dag.hierarchy_parent(n);
    uint32_t need = hp != kNone && !cut.is_split(hp) ? hp : kNone;
    for (uint32_t p : dag.parents(n))
      if (need == kNone && !cut.is_split(p)) need = p;
    if (need != kNone) {
      todo.push_back(need);
      continue;
    }
    cut.split(n);
    todo.pop_back();
  }
  const std::vector<VertexId> front = cut_front(model, cut);
  server::Session session(f.catalogue, server::ServerLimits{});
  for (const auto& message : {hello, protocol::encode(protocol::Open{f.name, front, StreamMode::dag})}) {
    protocol::Frame frame;
    frame.type = protocol::MessageType(message[4]);
    frame.payload.assign(message.begin() + protocol::kFrameHeaderBytes, message.end());
    session.receive(std::move(frame));
  }
  while (session.pump()) {
  }
  EXPECT_EQ(session.error(), std::nullopt) << session.error_text();
  EXPECT_TRUE(dag_mode(session).opened());
  EXPECT_EQ(dag_mode(session).cut().split_count(), cut.split_count()) << "a real cut's front resumes as that cut";
  client::StreamingClient good("127.0.0.1", tcp.port(), dag_options(DagTraversal::linear, 5000, 300, 1.0f));
  good.open(f.name);
  EXPECT_GT(good.frame(orbit_path(f.hierarchy, 4, 0.2f).back()).vsplits, 0u);
}

// An in-process transport to `session` that loses the connection once `*left` more server frames have come
// (negative: never).
std::unique_ptr<client::Transport> losing_transport(std::shared_ptr<server::Session> session, std::shared_ptr<int> left,
                                                    const server::ServerLimits& limits) {
  client::LocalEndpoint endpoint;
  endpoint.receive = [session](protocol::Frame frame) { session->receive(std::move(frame)); };
  endpoint.next_frame = [session, left]() -> server::Buffer {
    if (*left == 0) throw client::ConnectionError("test: connection lost");
    while (session->outbox().empty())
      if (!session->pump()) return nullptr;
    server::Buffer frame = std::move(session->outbox().front());
    session->outbox().pop_front();
    if (*left > 0) --*left;
    return frame;
  };
  return std::make_unique<client::LocalTransport>(std::move(endpoint), limits.max_client_message);
}

// A DAG client that loses its connection in the middle of an answer holds a cut (every prefix of an answer
// is one); resumed on another session, its mesh is that session's cut at once and after every frame.
TEST(DagStreaming, ResumedMidAnswerTheMeshStaysTheServersCut) {
  const Fixture& f = terrain();
  const ModelData& model = f.catalogue->find(f.name)->model();
  server::ServerLimits limits;
  limits.batch_splits = 8;
  const std::vector<Camera> path = orbit_path(f.hierarchy, 16, 0.3f);
  for (DagTraversal t : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time}) {
    SCOPED_TRACE(int(t));
    const auto first = std::make_shared<server::Session>(f.catalogue, limits);
    const auto left = std::make_shared<int>(-1);
    client::StreamingClient client(losing_transport(first, left, limits), dag_options(t, 0, 100, 1.0f));
    client.open(f.name);
    for (size_t i = 0; i < 8; ++i) client.frame(path[i]);
    *left = 1;  // one DAG_OPS of the next answer, then the connection is gone
    EXPECT_THROW(client.frame(path[8]), client::ConnectionError);
    const test::Faces held = faces_by_id(client.session().mesh());
    EXPECT_NE(held, cut_faces(model, session_cut(f, *first))) << "the loss was not in the middle of an answer";

    const auto second = std::make_shared<server::Session>(f.catalogue, limits);
    client.resume(losing_transport(second, std::make_shared<int>(-1), limits));
    std::string why;
    DagCut cut = session_cut(f, *second);
    ASSERT_TRUE(cut.check(&why)) << why;
    ASSERT_EQ(cut_faces(model, cut), held) << "the resumed cut is not the client's mesh";
    for (size_t i = 8; i < path.size(); ++i) {
      client.frame(path[i]);
      cut = session_cut(f, *second);
      ASSERT_TRUE(cut.check(&why)) << "frame " << i << ": " << why;
      ASSERT_EQ(faces_by_id(client.session().mesh()), cut_faces(model, cut)) << "frame " << i;
    }
  }
}

// With reconnect attempts (`stream --reconnect N`), a DAG client whose server goes away resumes on the one
// that comes back on the same port; the priority traversal keeps no cursor, so the path ends on the mesh an
// unbroken session ends on.
TEST(DagStreaming, ReconnectResumesOnARestartedServer) {
  const Fixture& f = terrain();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 12, 0.4f);
  const size_t half = path.size() / 2;
  client::ClientOptions options = dag_options(DagTraversal::priority, 0, 200, 1.0f);
  test::InProcess unbroken = in_process(f, options);
  for (const Camera& camera : path) unbroken.client->frame(camera);

  auto tcp = std::make_unique<server::TcpServer>(f.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp->start();
  const uint16_t port = tcp->port();
  options.reconnect_attempts = 8;
  options.reconnect_delay = std::chrono::milliseconds(20);
  std::atomic<int> told{0};
  options.on_reconnect = [&](const std::string&, uint32_t) { ++told; };
  client::StreamingClient client("127.0.0.1", port, options);
  client.open(f.name);
  for (size_t i = 0; i < half; ++i) client.frame(path[i]);
  tcp.reset();
  std::thread restart([&] {
    while (told < 2) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    tcp = std::make_unique<server::TcpServer>(f.catalogue, server::ServerLimits{}, "127.0.0.1", port);
    tcp->start();
  });
  for (size_t i = half; i < path.size(); ++i) client.frame(path[i]);
  restart.join();
  EXPECT_GE(told, 2);
  EXPECT_EQ(faces_by_id(client.session().mesh()), faces_by_id(unbroken.client->session().mesh()));
}

}  // namespace
}  // namespace pms
