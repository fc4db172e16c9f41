// kim-lee-kobbelt §6.3's variation (StreamMode::sender_plain, Fig. 10 middle column): the sender-driven
// mode's splits with the client's actual cut vertices and no refinement info, for a viewer that does not
// refine. Its client's mesh is the server's view of it (the front equals the session's tags, the faces
// those of truly selective refinement by the same splits), its packets cost what view-independent ones
// do, and OPEN refuses the flag where it does not belong.
#include <gtest/gtest.h>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <set>
#include <span>

#include "client/local_transport.h"
#include "client/streaming_client.h"
#include "common/error.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/packet_bits.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/plain_packets.h"
#include "server/selective_streaming.h"
#include "server/session.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms {
namespace {

using protocol::StreamMode;
using test::faces_by_id;
using test::Fixture;
using test::local_faces;
using test::make_fixture;
using test::orbit_path;

const Fixture& terrain() {
  return test::terrain_fixture(30000, 7);
}

client::ClientOptions options_for(StreamMode mode, float tolerance = 1.0f) {
  client::ClientOptions options{tolerance};
  options.mode = mode;
  return options;
}

using test::InProcess;

InProcess in_process(const Fixture& f, StreamMode mode, float tolerance) {
  static const server::ServerLimits limits;
  return test::in_process(f, options_for(mode, tolerance), limits);
}

// The splits a client holds, in the order they arrived: its hierarchy allocates each split's children as
// the next pair of slots after the roots.
std::vector<uint32_t> arrival_order(client::ClientSession& session, const ModelData& model) {
  VertexHierarchy& h = session.hierarchy();
  std::vector<uint32_t> nodes;
  for (uint32_t slot = h.root_count(); slot < h.size(); slot += 2) nodes.push_back(model.find(h.id(h.parent(slot))));
  return nodes;
}

// Truly selective refinement (Kim & Lee 2001) of the model by `nodes` in that order, from the fundamental
// cut vertices of the model's own split records: what the client's mesh must be.
test::Faces selective_refinement_by(const ModelData& model, const std::vector<uint32_t>& nodes) {
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  for (uint32_t node : nodes) {
    hierarchy.add_split(split_record(model, node));
    EXPECT_TRUE(mesh.vsplit(hierarchy.find(model.id(node))).done) << to_string(model.id(node));
  }
  return faces_by_id(mesh);
}

TEST(SenderPlain, ClientMeshIsTheServersViewOfItAlongAPath) {
  const Fixture& f = terrain();
  const ModelData model = model_of(f.snapped);
  InProcess p = in_process(f, StreamMode::sender_plain, 1.0f);
  client::ClientSession& session = p.client->session();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.9f);
  uint64_t faces = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    const client::FrameReport r = p.client->frame(path[i]);
    EXPECT_TRUE(r.requested) << "a client that does not refine asks every frame";
    if (i == 0) {
      EXPECT_EQ(faces_by_id(session.mesh()), local_faces(f.snapped, path[0], 1.0f))
          << "the first view from the base mesh";
    }
    // It never coarsens, and every split it holds is made: its front is its hierarchy's leaves ...
    EXPECT_GE(r.faces, faces);
    faces = r.faces;
    const VertexHierarchy& h = session.hierarchy();
    std::set<uint32_t> mesh_front, server_front;
    for (uint32_t slot : session.mesh().active_vertices()) mesh_front.insert(model.find(h.id(slot)));
    for (uint32_t slot = 0; slot < h.size(); ++slot) EXPECT_EQ(h.is_leaf(slot), session.mesh().is_active(slot));
    // ... and the server's active tags, from which it named the actual cut vertices.
    const ActiveTags tags = p.session->front_tags();
    for (uint32_t n = tags.next_active(0); n != UINT32_MAX; n = tags.next_active(n + 1)) server_front.insert(n);
    EXPECT_EQ(mesh_front, server_front) << "frame " << r.frame;
  }
  // The actual cut vertices were each split's ActiveAncestor(v̂) on the client's mesh when it arrived: the
  // faces are those of truly selective refinement by the same splits in the same order.
  EXPECT_EQ(faces_by_id(session.mesh()), selective_refinement_by(model, arrival_order(session, model)));
  // Every vsplit crosses the network once: a second lap brings no split.
  uint64_t lap2 = 0;
  for (const Camera& camera : path) lap2 += p.client->frame(camera).vsplits;
  EXPECT_EQ(lap2, 0u);
}

// The same view asks the same splits of the sender-driven mode: the plain option changes the coding only.
TEST(SenderPlain, SameSplitsAsSenderDrivenForOneView) {
  const Fixture& f = terrain();
  const Camera close = orbit_path(f.hierarchy, 8, 0.4f).back();
  InProcess plain = in_process(f, StreamMode::sender_plain, 0.5f);
  InProcess sender = in_process(f, StreamMode::sender_driven, 0.5f);
  plain.client->frame(close);
  sender.client->frame(close);
  EXPECT_GT(plain.client->session().splits_received(), 100u);
  EXPECT_EQ(plain.client->session().splits_received(), sender.client->session().splits_received());
  EXPECT_EQ(faces_by_id(plain.client->session().mesh()), faces_by_id(sender.client->session().mesh()));
  EXPECT_EQ(faces_by_id(plain.client->session().mesh()), local_faces(f.snapped, close, 0.5f));
}

struct PacketCost {
  uint64_t splits = 0;
  uint64_t plain_bits = 0, vi_bits = 0, sender_bits = 0;  // the same splits coded three ways
  double bytes_per_packet = 0;                            // VSPLITS frames as received, per packet
};

// One close view in `mode`; for the splits it brought, what their packets cost as received and what the
// same splits would cost as view-independent packets (fundamental cut ids, no refinement info) and as
// sender-driven ones.
PacketCost packet_cost(const Fixture& f, const Camera& camera, StreamMode mode) {
  const ModelData model = model_of(f.snapped);
  InProcess p = in_process(f, mode, 1.0f);
  const uint64_t base_bytes = p.client->counters().bytes_down;
  p.client->frame(camera);
  client::ClientSession& session = p.client->session();
  protocol::StreamContext full = session.context(), none = session.context();
  full.has_refinement = true;
  none.has_refinement = false;
  PacketCost c;
  const VertexHierarchy& h = session.hierarchy();
  for (uint32_t slot = h.root_count(); slot < h.size(); slot += 2) {
    const uint32_t node = model.find(h.id(h.parent(slot)));
    SplitRecord received = split_record(model, node);
    received.cut_l = h.cut_left(h.parent(slot));
    received.cut_r = h.cut_right(h.parent(slot));
    c.plain_bits += protocol::packet_bits(received, none).total();
    c.vi_bits += protocol::packet_bits(split_record(model, node), none).total();
    c.sender_bits += protocol::packet_bits(split_record(model, node), full).total();
    ++c.splits;
  }
  c.bytes_per_packet = double(p.client->counters().bytes_down - base_bytes) / double(std::max<uint64_t>(1, c.splits));
  return c;
}

void expect_plain_costs_what_view_independent_does(const Fixture& f, const Camera& close) {
  const PacketCost plain = packet_cost(f, close, StreamMode::sender_plain);
  const PacketCost vi = packet_cost(f, close, StreamMode::view_independent);
  const PacketCost sender = packet_cost(f, close, StreamMode::sender_driven);
  std::printf(
      "%s close view: bytes/packet plain %.2f (%llu splits), vi %.2f (%llu), sender %.2f (%llu); "
      "plain splits coded as vi %.2f, as sender %.2f\n",
      f.name.c_str(), plain.bytes_per_packet, (unsigned long long)plain.splits, vi.bytes_per_packet,
      (unsigned long long)vi.splits, sender.bytes_per_packet, (unsigned long long)sender.splits,
      double(plain.vi_bits) / 8 / double(plain.splits), double(plain.sender_bits) / 8 / double(plain.splits));
  ASSERT_GT(plain.splits, 100u);
  // Same fields as a view-independent packet, and an actual cut vertex is an ancestor-or-self of the
  // fundamental one, so its id is never longer: never more bits for the same splits.
  EXPECT_LE(plain.plain_bits, plain.vi_bits);
  // The refinement info is what it leaves out: the sender-driven packets of the same splits cost more.
  EXPECT_LT(plain.plain_bits, plain.sender_bits);
  // On the wire, against a real view-independent session (a different set of splits: the PM prefix): the
  // packets are about as large. 10 % covers the other splits' id depths and the batch headers.
  EXPECT_LE(plain.bytes_per_packet, 1.10 * vi.bytes_per_packet);
  EXPECT_LT(plain.bytes_per_packet, sender.bytes_per_packet);
  // A real sender-driven session brings the same splits, each dearer by its refinement info.
  EXPECT_EQ(plain.splits, sender.splits);
}

TEST(SenderPlain, PacketsCostAboutWhatViewIndependentOnesDoTerrain) {
  const Fixture& f = terrain();
  expect_plain_costs_what_view_independent_does(f, orbit_path(f.hierarchy, 8, 0.4f).back());
}

TEST(SenderPlain, PacketsCostAboutWhatViewIndependentOnesDoBunny) {
  PMS_REQUIRE_SHARED_MODEL(file, "bunny.ply.xz");
  Mesh mesh = load_mesh(file.string());
  clean_mesh(mesh);
  const Fixture f = make_fixture(mesh, "bunny");
  expect_plain_costs_what_view_independent_does(f, orbit_path(f.hierarchy, 8, 0.0f).back());
}

TEST(SenderPlain, ResumedSessionEndsWhereAnUnbrokenOneDoes) {
  const Fixture& f = terrain();
  server::TcpServer tcp(f.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 1.1f);
  client::StreamingClient client("127.0.0.1", tcp.port(), options_for(StreamMode::sender_plain, 0.5f));
  client.open(f.name);
  for (size_t i = 0; i < path.size() / 2; ++i) client.frame(path[i]);
  const uint64_t before = client.session().splits_received();
  client.resume("127.0.0.1", tcp.port());  // OPEN with the leaves held: the server rebuilds its tags
  for (size_t i = path.size() / 2; i < path.size(); ++i) client.frame(path[i]);
  EXPECT_GT(client.session().splits_received(), before);
  client::StreamingClient unbroken("127.0.0.1", tcp.port(), options_for(StreamMode::sender_plain, 0.5f));
  unbroken.open(f.name);
  for (const Camera& camera : path) unbroken.frame(camera);
  EXPECT_EQ(client.session().splits_received(), unbroken.session().splits_received());
  EXPECT_EQ(faces_by_id(client.session().mesh()), faces_by_id(unbroken.session().mesh()));
}

// The encoder takes one ActualCuts per node, on the sides the split has, for a context without refinement info.
TEST(SenderPlain, PlainBatchEncoderRefusesCutsThatDoNotFitTheSplits) {
  const Fixture& f = terrain();
  const ModelData& model = f.catalogue->find(f.name)->model();
  protocol::StreamContext wire = f.catalogue->find(f.name)->context;
  wire.has_refinement = false;
  const uint32_t node = model.split_order[0];
  const auto side = [&](uint32_t cut) {
    return cut == kNone ? kNone : active_ancestor(model, ActiveTags(model.root_count), cut);
  };
  const ActualCuts actual{side(model.cut_left[node]), side(model.cut_right[node])};
  const std::vector<uint32_t> nodes{node};
  const std::vector<uint8_t> frame = server::encode_plain_batch(model, wire, 7, true, nodes, std::vector{actual});
  const protocol::VSplits back = protocol::decode_vsplits(std::span(frame).subspan(protocol::kFrameHeaderBytes), wire);
  ASSERT_EQ(back.splits.size(), 1u);
  EXPECT_EQ(back.frame, 7u);
  EXPECT_EQ(back.splits[0].vs, model.id(node));
  EXPECT_EQ(back.splits[0].cut_l, actual.left == kNone ? kNoVertex : model.id(actual.left))
      << "a root: the base mesh's";
  EXPECT_THROW(server::encode_plain_batch(model, wire, 7, true, nodes, {}), Error) << "no cuts for the node";
  ActualCuts other_side = actual;
  other_side.left = actual.left == kNone ? 0 : kNone;
  EXPECT_THROW(server::encode_plain_batch(model, wire, 7, true, nodes, std::vector{other_side}), Error)
      << "a side the split does not have, or none where it has one";
  protocol::StreamContext with_info = wire;
  with_info.has_refinement = true;
  EXPECT_THROW(server::encode_plain_batch(model, with_info, 7, true, nodes, std::vector{actual}), Error);
}

// OPEN flags (docs/protocol.md): bit 2 = plain, an option of the sender-driven mode only.
std::vector<uint8_t> open_with_flags(const std::string& model, uint8_t flags, const std::vector<int>& front_bits,
                                     uint32_t trees) {
  protocol::Writer w(protocol::MessageType::open);
  w.string(model, protocol::kMaxNameBytes, "model");
  w.u8(flags);
  if (flags & 1) {
    w.u32(trees);
    for (int b : front_bits) w.bits(uint64_t(b), 1);
  }
  return w.finish();
}

TEST(SenderPlain, HostileOpenFlagsGetAnError) {
  const Fixture& f = terrain();
  server::TcpServer tcp(f.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  const auto hello = protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"});
  const uint32_t roots = f.hierarchy.root_count;
  using protocol::ErrorCode;
  const auto answer = [&](uint8_t flags, uint32_t trees) {
    const std::vector<int> lone_roots(trees, 0);  // the front of the base mesh
    return test::send_raw(tcp.port(), {hello, open_with_flags(f.name, flags, lone_roots, trees)});
  };
  EXPECT_EQ(answer(2 | 4, 0), ErrorCode::bad_message) << "plain with view-independent";
  EXPECT_EQ(answer(1 | 2 | 4, roots), ErrorCode::bad_message) << "plain with view-independent, resuming";
  EXPECT_EQ(answer(16 | 4, 0), ErrorCode::bad_message) << "an unknown bit beside plain";
  EXPECT_EQ(answer(8 | 4, 0), ErrorCode::bad_message) << "the DAG bit beside plain";
  EXPECT_EQ(answer(0xFF, roots), ErrorCode::bad_message) << "every bit";
  EXPECT_EQ(answer(1 | 4, roots + 1), ErrorCode::bad_id) << "a plain resume over more trees than the model has";
  // The server goes on serving a good plain session.
  client::StreamingClient good("127.0.0.1", tcp.port(), options_for(StreamMode::sender_plain));
  good.open(f.name);
  good.frame(orbit_path(f.hierarchy, 4, 0.2f).back());
  EXPECT_GT(good.session().splits_received(), 0u);
}

}  // namespace
}  // namespace pms
