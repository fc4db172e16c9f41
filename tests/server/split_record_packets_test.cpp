// Sender-driven VSPLITS packets as v_s's id and the compact split record (issue 19, docs/protocol.md
// "VSPLITS", "CODEC"): a flight over loopback gives every frame the mesh local refinement gives, for fewer
// bytes than the same splits as version 3 packets; hostile records fail the client with a clear error.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "client/client_session.h"
#include "client/link.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "common/error.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/vertex_id.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms {
namespace {

using test::Fixture;

// Passes frames through, and prices each VSPLITS as protocol version 3 sent it: a shadow client decodes
// the records against its own hierarchy and encodes the batch again without them.
class PricingTransport : public client::Transport {
 public:
  explicit PricingTransport(std::unique_ptr<client::Transport> inner) : inner_(std::move(inner)) {}
  void send(const std::vector<uint8_t>& frame) override { inner_->send(frame); }
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override {
    std::optional<protocol::Frame> frame = inner_->receive(timeout);
    if (!frame) return frame;
    const uint64_t bytes = protocol::kFrameHeaderBytes + frame->payload.size();
    if (frame->type == protocol::MessageType::base) shadow_.on_base(protocol::decode_base(frame->payload));
    if (frame->type == protocol::MessageType::codec) {
      shadow_.on_codec(protocol::decode_codec(frame->payload, shadow_.context()));
      codec_bytes += bytes;
    }
    if (frame->type == protocol::MessageType::vsplits) {
      const protocol::VSplits batch = protocol::decode_vsplits(frame->payload, shadow_.context());
      shadow_.on_vsplits(batch);
      protocol::StreamContext v3 = shadow_.context();
      v3.records = nullptr;
      v3.held = nullptr;
      vsplits_bytes += bytes;
      v3_bytes += protocol::encode(batch, v3).size();
      splits += batch.splits.size();
    }
    return frame;
  }
  client::LinkCounters counters() const override { return inner_->counters(); }

  uint64_t codec_bytes = 0, vsplits_bytes = 0, v3_bytes = 0, splits = 0;

 private:
  std::unique_ptr<client::Transport> inner_;
  client::ClientSession shadow_;
};

// Flies `path` at tau = 1 px: every frame's mesh must be local refinement's; returns the pricing.
void fly_and_compare(const Fixture& f, const std::vector<Camera>& path) {
  server::TcpServer server(f.catalogue, {}, "127.0.0.1", 0);
  server.start();
  auto pricing = std::make_unique<PricingTransport>(std::make_unique<client::Link>("127.0.0.1", server.port()));
  PricingTransport& priced = *pricing;
  client::StreamingClient client(std::move(pricing), client::ClientOptions{1.0f});
  client.open(f.name);
  ASSERT_TRUE(client.session().context().records) << "every model streams split records";
  for (const Camera& camera : path) {
    const client::FrameReport r = client.frame(camera);
    ASSERT_EQ(test::faces_by_id(client.session().mesh()), test::local_faces(f.snapped, camera, 1.0f))
        << "frame " << r.frame << " differs from local refinement";
    ASSERT_EQ(test::vertices_by_id(client.session().mesh()), test::local_vertices(f.snapped, camera, 1.0f))
        << "frame " << r.frame << ": positions, normals or colors differ from local refinement's";
  }
  ASSERT_GT(priced.splits, 0u);
  EXPECT_LT(priced.vsplits_bytes + priced.codec_bytes, priced.v3_bytes);
  std::printf(
      "[ records  ] %s: %llu splits, VSPLITS %llu bytes (%.1f bits/split) + CODEC %llu; as version 3: %llu "
      "bytes (%.1f bits/split)\n",
      f.name.c_str(), (unsigned long long)priced.splits, (unsigned long long)priced.vsplits_bytes,
      8.0 * double(priced.vsplits_bytes) / double(priced.splits), (unsigned long long)priced.codec_bytes,
      (unsigned long long)priced.v3_bytes, 8.0 * double(priced.v3_bytes) / double(priced.splits));
}

const Fixture& terrain() {
  return test::terrain_fixture(60000, 5);
}

TEST(SenderDrivenRecords, TerrainFlightGivesLocalRefinementsMeshesForFewerBytes) {
  fly_and_compare(terrain(), test::orbit_path(terrain().hierarchy, 12, 0.3f));
}

TEST(SenderDrivenRecords, BunnyFlightGivesLocalRefinementsMeshesForFewerBytes) {
  PMS_REQUIRE_SHARED_MODEL(file, "bunny.ply.xz");
  Mesh mesh = load_mesh(file.string());
  clean_mesh(mesh);
  const Fixture f = test::make_fixture(mesh, "bunny");
  fly_and_compare(f, test::orbit_path(f.hierarchy, 8, 0.0f));
}

TEST(SenderDrivenRecords, AModelWithNormalsAndColorsGivesLocalRefinementsValues) {
  const Fixture& f = test::attributed_terrain();
  fly_and_compare(f, test::orbit_path(f.hierarchy, 8, 0.1f));
}

TEST(SenderDrivenRecords, HorseFlightCarriesItsNormals) {
  PMS_REQUIRE_SHARED_MODEL(file, "horse.ply.xz");
  Mesh mesh = load_mesh(file.string());
  clean_mesh(mesh);
  ASSERT_TRUE(mesh.has_normals());
  const Fixture f = test::make_fixture(mesh, "horse");
  fly_and_compare(f, test::orbit_path(f.hierarchy, 6, 0.0f));
}

// A server that says what it was given to say: HELLO_OK, BASE, CODEC, then the VSPLITS answers.
class ScriptedServer : public client::Transport {
 public:
  explicit ScriptedServer(std::deque<protocol::Frame> frames) : frames_(std::move(frames)) {}
  void send(const std::vector<uint8_t>&) override {}
  std::optional<protocol::Frame> receive(std::chrono::milliseconds) override {
    if (frames_.empty()) throw client::ConnectionError("the script ended");
    protocol::Frame f = std::move(frames_.front());
    frames_.pop_front();
    return f;
  }
  client::LinkCounters counters() const override { return {}; }

 private:
  std::deque<protocol::Frame> frames_;
};

protocol::Frame frame_of(const std::vector<uint8_t>& bytes) {
  return {protocol::MessageType(bytes[4]), {bytes.begin() + protocol::kFrameHeaderBytes, bytes.end()}};
}

// The terrain's first internal roots' packets, as the server sends them to a fresh session.
std::vector<uint32_t> root_splits(const server::ServedModel& model, size_t count) {
  std::vector<uint32_t> nodes;
  for (uint32_t r = 0; r < model.model().root_count && nodes.size() < count; ++r)
    if (!model.model().is_leaf(r)) nodes.push_back(r);
  return nodes;
}

// The client's error for a session whose answer to the first VIEW is `vsplits`.
std::string client_error(const protocol::Frame& vsplits) {
  const Fixture& f = terrain();
  const server::ServedModel& model = *f.catalogue->find("terrain");
  std::deque<protocol::Frame> script{frame_of(protocol::encode(protocol::HelloOk{})), frame_of(*model.base_frame),
                                     frame_of(*model.tables->records().codec_frame), vsplits};
  client::StreamingClient client(std::make_unique<ScriptedServer>(std::move(script)), client::ClientOptions{1.0f});
  client.open("terrain");
  try {
    client.frame(test::orbit_path(f.hierarchy, 8, 2.4f).back());
  } catch (const client::ConnectionError& e) {
    return std::string("no error but the end of the script: ") + e.what();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// Every single bit of `good` flipped after the header (frame, flags, count: 9 bytes), decoded by a client
// of `model`: the decoder refuses it with a ProtocolError (its text kept), or what it decodes is a batch of
// splits, which `check` looks at; never anything else.
struct Flips {
  std::vector<std::string> errors;
  size_t decoded = 0;
};
Flips flip_every_bit(const server::ServedModel& model, const protocol::Frame& good,
                     const std::function<void(const protocol::VSplits&)>& check) {
  client::ClientSession session;
  session.on_base(protocol::decode_base(frame_of(*model.base_frame).payload));
  session.on_codec(protocol::decode_codec(frame_of(*model.tables->records().codec_frame).payload, session.context()));
  Flips flips;
  for (size_t bit = 8 * 9; bit < 8 * good.payload.size(); ++bit) {
    std::vector<uint8_t> flipped = good.payload;
    flipped[bit / 8] ^= uint8_t(1u << (bit % 8));
    try {
      check(protocol::decode_vsplits(flipped, session.context()));
      ++flips.decoded;
    } catch (const protocol::ProtocolError& e) {
      flips.errors.push_back(e.what());
    }
  }
  // The whole batch, unharmed, is accepted by the same client.
  check(protocol::decode_vsplits(good.payload, session.context()));
  return flips;
}

size_t errors_naming(const Flips& flips, const std::string& needle) {
  return size_t(std::count_if(flips.errors.begin(), flips.errors.end(),
                              [&](const std::string& e) { return e.find(needle) != std::string::npos; }));
}

TEST(SenderDrivenRecords, HostileRecordsFailTheClientWithAClearError) {
  const server::ServedModel& model = *terrain().catalogue->find("terrain");
  const std::vector<uint32_t> roots = root_splits(model, 4);
  ASSERT_EQ(roots.size(), 4u);
  const protocol::Frame good = frame_of(model.tables->packets().encode(1, true, roots));

  // Truncated: the last record loses its tail.
  protocol::Frame truncated = good;
  truncated.payload.resize(truncated.payload.size() - 2);
  EXPECT_NE(client_error(truncated).find("VSPLITS: packet 3"), std::string::npos) << client_error(truncated);

  // A split of a node the client does not hold (a root's child before the root's split), one split twice.
  const uint32_t child = model.model().first_child[roots[0]];
  if (!model.model().is_leaf(child)) {
    const std::string e = client_error(frame_of(model.tables->packets().encode(1, true, std::vector<uint32_t>{child})));
    EXPECT_NE(e.find("is not a vertex the receiver holds"), std::string::npos) << e;
  }
  const std::string twice =
      client_error(frame_of(model.tables->packets().encode(1, true, std::vector<uint32_t>{roots[0], roots[0]})));
  EXPECT_NE(twice.find("split a second time"), std::string::npos) << twice;

  // Code words the tables lack and values off the grid are among the refusals of single flipped bits.
  const Flips flips =
      flip_every_bit(model, good, [](const protocol::VSplits& batch) { EXPECT_GT(batch.splits.size(), 0u); });
  const size_t record_errors = errors_naming(flips, ": record: ");
  EXPECT_GT(record_errors, 0u) << "no flipped bit made a record SplitCodec::decode refuses";
  std::printf("[ records  ] %zu bit flips: %zu refused by the record decoder, %zu still decode\n",
              8 * good.payload.size() - 72, record_errors, flips.decoded);
}

// The same with v_t's normal and color in the records: a flip there is refused (a normal off the octahedral
// square or an edge point's mirror image, a code word the tables lack) or decodes to a unit normal.
TEST(SenderDrivenRecords, HostileAttributesFailTheClientWithAClearError) {
  const server::ServedModel& model = *test::attributed_terrain().catalogue->find("attributed");
  const protocol::Frame good = frame_of(model.tables->packets().encode(1, true, root_splits(model, 4)));
  const Flips flips = flip_every_bit(model, good, [](const protocol::VSplits& batch) {
    for (const SplitRecord& s : batch.splits) {
      ASSERT_TRUE(s.has_normal && s.has_color);
      EXPECT_NEAR(
          std::sqrt(s.normal_t[0] * s.normal_t[0] + s.normal_t[1] * s.normal_t[1] + s.normal_t[2] * s.normal_t[2]), 1.0,
          1e-5);
    }
  });
  EXPECT_GT(errors_naming(flips, ": record: normal") + errors_naming(flips, ": record: color"), 0u)
      << "no flipped bit reached the attributes' checks";
  EXPECT_GT(flips.decoded, 0u);
}

TEST(SenderDrivenRecords, ACodecThatDoesNotFitTheBaseIsRefused) {
  const server::ServedModel& model = *terrain().catalogue->find("terrain");
  client::ClientSession session;
  session.on_base(protocol::decode_base(frame_of(*model.base_frame).payload));
  protocol::StreamContext other = session.context();
  other.root_count += 1;
  other.tree_id_bits = 32;
  const protocol::Frame codec = frame_of(*model.tables->records().codec_frame);
  try {
    protocol::decode_codec(codec.payload, other);
    ADD_FAILURE() << "tables for another root count were accepted";
  } catch (const protocol::ProtocolError& e) {
    EXPECT_EQ(e.code, protocol::ErrorCode::bad_message);
    EXPECT_NE(std::string(e.what()).find("CODEC: tables"), std::string::npos) << e.what();
  }
  std::vector<uint8_t> trailing = codec.payload;
  trailing.push_back(0);
  EXPECT_THROW(protocol::decode_codec(trailing, session.context()), protocol::ProtocolError);
  std::vector<uint8_t> cut(codec.payload.begin(), codec.payload.end() - 1);
  EXPECT_THROW(protocol::decode_codec(cut, session.context()), protocol::ProtocolError);
  // A BASE with normals and colors and tables without them (or the other way round) do not fit either.
  protocol::StreamContext attributed = session.context();
  attributed.has_normals = attributed.has_colors = true;
  EXPECT_THROW(protocol::decode_codec(codec.payload, attributed), protocol::ProtocolError);
  const server::ServedModel& with = *test::attributed_terrain().catalogue->find("attributed");
  client::ClientSession attributed_session;
  attributed_session.on_base(protocol::decode_base(frame_of(*with.base_frame).payload));
  EXPECT_NO_THROW(
      protocol::decode_codec(frame_of(*with.tables->records().codec_frame).payload, attributed_session.context()));
  EXPECT_THROW(protocol::decode_codec(frame_of(*with.tables->records().codec_frame).payload, session.context()),
               protocol::ProtocolError);
}

}  // namespace
}  // namespace pms
