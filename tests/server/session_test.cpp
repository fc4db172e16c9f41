// The session logic without sockets, driven the way a hostile client would: resume fronts that do not
// cover the model's trees, VIEW floods, and large fronts and answers that must be worked through in
// bounded slices.
#include <gtest/gtest.h>
#include <algorithm>
#include <set>

#include "builder/build.h"
#include "client/client_session.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/dag_mode.h"
#include "server/limits.h"
#include "server/session.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/vertex_id.h"
#include "frame_of.h"
#include "test_support.h"

namespace pms {
namespace {

struct Model {
  Hierarchy hierarchy;
  std::shared_ptr<const server::Catalogue> catalogue;
};

const Model& terrain() {
  static const Model m = [] {
    Model model;
    BuildResult built = build_progressive_mesh(make_terrain(20000, 3), BuildOptions{});
    model.hierarchy = std::move(built.hierarchy);
    const std::string path = (test::temp_dir() / "terrain.pms").string();
    write_pms(path, model.hierarchy, built.stats);
    model.catalogue = server::Catalogue::open({path});
    return model;
  }();
  return m;
}

using test::frame_of;

Camera close_camera(const Hierarchy& h) {
  Camera c;
  for (int k = 0; k < 3; ++k) c.target[k] = 0.5f * (h.bbox_min[k] + h.bbox_max[k]);
  std::copy_n(c.target, 3, c.eye);
  c.eye[1] += 0.4f * (h.bbox_max[0] - h.bbox_min[0]);
  c.eye[2] += 0.3f * (h.bbox_max[0] - h.bbox_min[0]);
  c.width = 640;
  c.height = 480;
  return c;
}

// What a client reads: every frame of the outbox, decoded, with the splits of each VSPLITS.
struct Reader {
  std::optional<protocol::StreamContext> context;
  client::ClientSession client;
  std::vector<protocol::ErrorCode> errors;
  std::vector<protocol::VSplits> batches;
  bool base = false;
  bool view_independent = false;  // its packets carry no refinement info

  void drain(server::Session& session) {
    auto& outbox = session.outbox();
    for (; !outbox.empty(); outbox.pop_front()) {
      const protocol::Frame frame = frame_of(*outbox.front());
      const protocol::ServerMessage m = protocol::decode_server_message(frame, context ? &*context : nullptr);
      if (const auto* b = std::get_if<protocol::Base>(&m)) {
        context = protocol::stream_context(*b);
        context->has_refinement = !view_independent;
        client.refinement_info = !view_independent;
        client.on_base(*b);
        base = true;
      } else if (const auto* c = std::get_if<protocol::Codec>(&m)) {
        client.on_codec(*c);  // split records decode against the hierarchy they make
        context = client.context();
      } else if (const auto* v = std::get_if<protocol::VSplits>(&m)) {
        if (context->records) client.on_vsplits(*v);
        batches.push_back(*v);
      } else if (const auto* e = std::get_if<protocol::ErrorMessage>(&m)) {
        errors.push_back(e->code);
      }
    }
  }
};

// Pumps until the session has nothing left to do, draining as a fast reader; returns the most work any
// one call did.
uint64_t run(server::Session& session, Reader& reader, const server::ServerLimits& limits) {
  uint64_t most = 0;
  for (int call = 0; call < 1000000 && session.has_work(); ++call) {
    session.pump();
    most = std::max(most, session.last_work());
    reader.drain(session);
  }
  EXPECT_FALSE(session.has_work()) << "the session never finished";
  EXPECT_LE(most, uint64_t(limits.slice_work) + 3 * 64) << "a slice is its budget plus one dependency chain";
  return most;
}

void greet(server::Session& session) {
  session.receive(frame_of(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "test"})));
  session.outbox().clear();
}

std::optional<protocol::ErrorCode> open_with(const std::vector<VertexId>& front) {
  const server::ServerLimits limits;
  server::Session session(terrain().catalogue, limits);
  greet(session);
  session.receive(frame_of(protocol::encode(protocol::Open{"terrain", front})));
  Reader reader;
  run(session, reader, limits);
  reader.drain(session);
  if (reader.errors.empty()) return std::nullopt;
  return reader.errors.front();
}

TEST(Session, ResumeFrontsMustCoverExactlyTheModelsTrees) {
  const uint32_t roots = terrain().hierarchy.root_count;
  std::vector<VertexId> all;
  for (uint32_t t = 0; t < roots; ++t) all.push_back({t, 1});
  EXPECT_EQ(open_with(all), std::nullopt) << "the base mesh's front resumes";
  std::vector<VertexId> fewer(all.begin(), all.end() - 1);
  EXPECT_EQ(open_with(fewer), protocol::ErrorCode::bad_id) << "a tree missing (the hang of issue 14)";
  std::vector<VertexId> more = all;
  more.push_back({roots, 1});
  EXPECT_EQ(open_with(more), protocol::ErrorCode::bad_id) << "a tree the model lacks";
  // Every leaf of the model, but one of them split: its children are not in the model.
  const Hierarchy& h = terrain().hierarchy;
  std::vector<VertexId> deeper;
  for (uint32_t n = 0; n < h.node_count(); ++n)
    if (h.is_leaf(n)) deeper.push_back(h.id(n));
  const VertexId leaf = deeper.back();
  deeper.back() = leaf.child(0);
  deeper.push_back(leaf.child(1));
  EXPECT_EQ(open_with(deeper), protocol::ErrorCode::bad_id) << "children of a real leaf";
}

// A resume of every leaf: checked and applied by pump() in slices, after which nothing is left to send.
TEST(Session, AValidResumeOfAFineFrontIsAppliedInSlices) {
  const Hierarchy& h = terrain().hierarchy;
  std::vector<VertexId> leaves;
  for (uint32_t n = 0; n < h.node_count(); ++n)
    if (h.is_leaf(n)) leaves.push_back(h.id(n));
  server::ServerLimits limits;
  limits.slice_work = 256;
  server::Session session(terrain().catalogue, limits);
  greet(session);
  session.receive(frame_of(protocol::encode(protocol::Open{"terrain", leaves})));
  EXPECT_FALSE(session.opened()) << "the front is checked by pump(), not by the message handler";
  Reader reader;
  run(session, reader, limits);
  EXPECT_TRUE(reader.base);
  EXPECT_TRUE(session.opened());
  EXPECT_EQ(session.front_tags().active_count(), leaves.size());
  // Every split is already held: a VIEW wants nothing.
  session.receive(frame_of(protocol::encode(protocol::View{close_camera(h), 0.0f, 1})));
  run(session, reader, limits);
  ASSERT_FALSE(reader.batches.empty());
  size_t splits = 0;
  for (const auto& b : reader.batches) splits += b.splits.size();
  EXPECT_EQ(splits, 0u);
}

TEST(Session, AViewFloodCostsOneAnswer) {
  const Hierarchy& h = terrain().hierarchy;
  server::ServerLimits limits;
  limits.slice_work = 512;
  limits.batch_splits = 64;
  const Camera camera = close_camera(h);

  server::Session single(terrain().catalogue, limits);
  greet(single);
  single.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}})));
  single.receive(frame_of(protocol::encode(protocol::View{camera, 0.5f, 1000})));
  Reader one;
  run(single, one, limits);

  server::Session flooded(terrain().catalogue, limits);
  greet(flooded);
  flooded.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}})));
  for (uint32_t f = 1; f <= 1000; ++f) {
    Camera c = camera;
    c.eye[0] += 0.001f * float(f % 7);
    if (f == 1000) c = camera;
    flooded.receive(frame_of(protocol::encode(protocol::View{c, 0.5f, f})));
    EXPECT_LE(flooded.last_work(), 0u) << "a VIEW is only recorded";
  }
  Reader many;
  run(flooded, many, limits);
  ASSERT_FALSE(many.batches.empty());
  for (size_t i = 0; i < many.batches.size(); ++i) {
    EXPECT_EQ(many.batches[i].frame, 1000u) << "only the newest VIEW is answered";
    EXPECT_EQ(many.batches[i].final, i + 1 == many.batches.size());
  }
  std::vector<VertexId> a, b;
  for (const auto& batch : one.batches)
    for (const auto& s : batch.splits) a.push_back(s.vs);
  for (const auto& batch : many.batches)
    for (const auto& s : batch.splits) b.push_back(s.vs);
  EXPECT_GT(a.size(), 500u);
  EXPECT_EQ(a, b);
}

// Profiled (serve --profile-phases), a sender-driven answer's time lands in the phases cheng-ooi's Table 1
// names for a sender: visibility, the front's update, the packets' search; never in the receiver's decode.
// Unprofiled, the same answer times nothing and is the same answer.
TEST(Session, ProfiledPhasesTimeTheSenderDrivenAnswerOnly) {
  const Camera camera = close_camera(terrain().hierarchy);
  const auto answer = [&](server::PhaseTimes* phases) {
    const server::ServerLimits limits;
    server::Session session(terrain().catalogue, limits);
    session.profile_phases(phases);
    greet(session);
    session.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}})));
    session.receive(frame_of(protocol::encode(protocol::View{camera, 0.5f, 1})));
    Reader reader;
    run(session, reader, limits);
    std::vector<VertexId> splits;
    for (const auto& batch : reader.batches)
      for (const auto& s : batch.splits) splits.push_back(s.vs);
    return splits;
  };
  server::PhaseTimes times;
  const std::vector<VertexId> profiled = answer(&times);
  EXPECT_EQ(profiled, answer(nullptr));
  ASSERT_GT(profiled.size(), 500u);
  const auto ns = [&](server::Phase p) { return times.ns[size_t(p)].load(); };
  EXPECT_GT(ns(server::Phase::send_base), 0u);
  EXPECT_GT(ns(server::Phase::determine_visibility), 0u);
  EXPECT_GT(ns(server::Phase::update_front), 0u);
  EXPECT_GT(ns(server::Phase::search_splits), 0u);
  EXPECT_EQ(ns(server::Phase::decode_ids), 0u) << "a sender-driven server decodes no id sets";
}

// A newer VIEW in the middle of an answer: nothing sent is sent again, and the client ends up with what
// one VIEW of the new camera from the same front would give.
TEST(Session, ANewerViewMidAnswerNeverResendsASplit) {
  const Hierarchy& h = terrain().hierarchy;
  server::ServerLimits limits;
  limits.slice_work = 128;
  limits.batch_splits = 32;
  server::Session session(terrain().catalogue, limits);
  greet(session);
  session.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}})));
  Reader reader;
  reader.drain(session);
  Camera camera = close_camera(h);
  session.receive(frame_of(protocol::encode(protocol::View{camera, 0.25f, 1})));
  for (int i = 0; i < 20; ++i) {
    session.pump();
    reader.drain(session);
  }
  camera.eye[0] += 0.2f * (h.bbox_max[0] - h.bbox_min[0]);
  session.receive(frame_of(protocol::encode(protocol::View{camera, 0.25f, 2})));
  run(session, reader, limits);
  std::set<std::pair<uint32_t, uint64_t>> seen;
  for (const auto& batch : reader.batches)
    for (const auto& s : batch.splits) EXPECT_TRUE(seen.insert({s.vs.tree, s.vs.node}).second) << to_string(s.vs);
  ASSERT_FALSE(reader.batches.empty());
  EXPECT_EQ(reader.batches.back().frame, 2u);
  EXPECT_TRUE(reader.batches.back().final);
}

TEST(Session, ViewIndependentAnswersAreSlicedToo) {
  const Hierarchy& h = terrain().hierarchy;
  server::ServerLimits limits;
  limits.slice_work = 256;
  server::Session session(terrain().catalogue, limits);
  greet(session);
  session.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}, protocol::StreamMode::view_independent})));
  session.receive(frame_of(protocol::encode(protocol::View{close_camera(h), 0.0f, 1})));
  Reader reader;
  reader.view_independent = true;
  run(session, reader, limits);
  size_t splits = 0;
  for (const auto& b : reader.batches) splits += b.splits.size();
  EXPECT_GT(splits, 1000u);
  EXPECT_TRUE(reader.batches.back().final);
}

// The plain option (kim-lee-kobbelt §6.3) names each split's actual cut vertices while it walks the front:
// the same bounded slices, and every split's cut vertices are leaves the client holds when it arrives.
TEST(Session, PlainAnswersAreSlicedAndNameHeldCutVertices) {
  const Hierarchy& h = terrain().hierarchy;
  server::ServerLimits limits;
  limits.slice_work = 256;
  server::Session session(terrain().catalogue, limits);
  greet(session);
  session.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}, protocol::StreamMode::sender_plain})));
  session.receive(frame_of(protocol::encode(protocol::View{close_camera(h), 0.0f, 1})));
  Reader reader;
  reader.view_independent = true;  // no refinement info in these packets either
  run(session, reader, limits);
  std::set<std::pair<uint32_t, uint64_t>> held;
  for (uint32_t t = 0; t < h.root_count; ++t) held.insert({t, 1});
  size_t splits = 0;
  for (const auto& b : reader.batches)
    for (const auto& s : b.splits) {
      ASSERT_TRUE(held.erase({s.vs.tree, s.vs.node})) << to_string(s.vs) << " is not a held leaf";
      for (VertexId cut : {s.cut_l, s.cut_r})
        if (is_vertex(cut)) {
          EXPECT_TRUE(held.count({cut.tree, cut.node})) << to_string(cut) << " is not a held leaf";
        }
      EXPECT_NE(s.cut_l, s.cut_r);
      held.insert({s.vs.tree, s.vs.child(0).node});
      held.insert({s.vs.tree, s.vs.child(1).node});
      ++splits;
    }
  EXPECT_GT(splits, 1000u);
  EXPECT_EQ(session.front_tags().active_count(), held.size());
  EXPECT_TRUE(reader.batches.back().final);
}

// The DAG mode: a DAG_VIEW is only recorded; one pump runs the traversal and every later pump sends one
// DAG_OPS of at most batch_splits operations. The first view's answer is the converged cut (work bounded by
// the cut: the priority walk and its splits); from the second on the message bounds the traversal's work
// (constant-time: at most N nodes evaluated and N operations per phase), and the cut the load of the session's
// compact cut into the thread's dense one and its store (a unit per split node).
TEST(Session, DagAnswersAreBoundedSlices) {
  const Hierarchy& h = terrain().hierarchy;
  server::ServerLimits limits;
  limits.batch_splits = 128;
  server::Session session(terrain().catalogue, limits);
  greet(session);
  session.receive(frame_of(protocol::encode(protocol::Open{"terrain", {}, protocol::StreamMode::dag})));
  protocol::DagView request;
  request.view = {close_camera(h), 8.0f, 1};
  request.traversal = DagTraversal::constant_time;
  request.max_ops = 500;
  const size_t nodes = terrain().catalogue->find("terrain")->tables->dag().size();
  for (int view = 0; view < 2; ++view) {
    SCOPED_TRACE(view);
    session.receive(frame_of(protocol::encode(request)));
    EXPECT_EQ(session.last_work(), 0u) << "a DAG_VIEW is only recorded";
    ASSERT_TRUE(session.pump());
    EXPECT_GT(session.last_work(), 0u);
    if (view == 0) {
      EXPECT_LE(session.last_work(), 8u * nodes) << "the converged first answer: the cut's walk and its splits";
    } else {
      const auto& mode = dynamic_cast<const server::DagSessionMode&>(*session.session_mode());
      EXPECT_LE(session.last_work(), 4u * request.max_ops + mode.cut().split_count())
          << "the traversal: N evaluated and N made per phase, and the cut's load and store";
    }
    size_t batches = 0;
    while (session.pump()) {
      ++batches;
      EXPECT_LE(session.last_work(), limits.batch_splits) << "one DAG_OPS a pump";
    }
    EXPECT_GT(batches, 1u);
    request.view = {close_camera(h), 0.0f, 2};  // much finer: N-limited work
  }
}

}  // namespace
}  // namespace pms
