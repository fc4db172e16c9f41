// The DAG mode over loopback (StreamMode::dag, zheng-chan 2006 §4–5): after every frame the thin client's
// mesh is the server's cut of the DAG, whatever the traversal; BUDGET mode never exceeds the budget on any
// frame; the priority traversal with a large N reaches local refinement's mesh for the view; hostile
// DAG_VIEW messages get ERROR and the server goes on serving others.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "client/local_transport.h"
#include "client/streaming_client.h"
#include "io/shapes.h"
#include "pm/hierarchy.h"
#include "pm/split_record.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "refine/dag.h"
#include "refine/dag_cut.h"
#include "refine/dag_traversal.h"
#include "refine/selective_mesh.h"
#include "refine/vertex_hierarchy.h"
#include "server/catalogue.h"
#include "server/dag_mode.h"
#include "server/limits.h"
#include "server/session.h"
#include "server/tcp_server.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using protocol::StreamMode;
using test::Fixture;
using test::faces_by_id;
using test::make_fixture;
using test::orbit_path;

const Fixture& terrain() {
  static const Fixture f = make_fixture(make_terrain(30000, 7), "terrain");
  return f;
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
const server::DagSessionMode& dag_mode(const test::InProcess& p) {
  return dynamic_cast<const server::DagSessionMode&>(*p.session->session_mode());
}

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
    const DagCut& cut = dag_mode(p).cut();
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
  EXPECT_GT(p.client->session().mesh().face_count(), f.catalogue->find(f.name)->dag->base_faces()) << "a view with detail";
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
    EXPECT_TRUE(dag_mode(p).cut().check(&why)) << why;
  }
}

// A DAG session holds its cut, about a byte per node, and a few KB of scratch between answers.
TEST(DagStreaming, StateIsAboutAByteANode) {
  const Fixture& f = terrain();
  test::InProcess p = in_process(f, dag_options(DagTraversal::priority, 0, 300, 1.0f));
  for (const Camera& c : orbit_path(f.hierarchy, 6, 0.0f)) p.client->frame(c);
  const size_t nodes = f.catalogue->find(f.name)->dag->size();
  EXPECT_GT(p.session->state_bytes(), nodes);
  EXPECT_LT(p.session->state_bytes(), 4 * nodes + (64u << 10));
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
  EXPECT_EQ(test::send_raw(tcp.port(), {hello, protocol::encode(protocol::Open{f.name, {VertexId{0, 1}}, StreamMode::dag})}),
            ErrorCode::bad_message)
      << "a resume front";
  // The server goes on serving a good DAG session.
  client::StreamingClient good("127.0.0.1", tcp.port(), dag_options(DagTraversal::linear, 5000, 300, 1.0f));
  good.open(f.name);
  const client::FrameReport report = good.frame(orbit_path(f.hierarchy, 4, 0.2f).back());
  EXPECT_GT(report.vsplits, 0u);
  EXPECT_LE(report.faces, 5000u);
}

}  // namespace
}  // namespace pms
