// A model file replaced under its name while clients fly it (issue 45; docs/protocol.md, "Versions"): a
// reload builds the next catalogue and swaps it in. A TCP session opened before keeps its model to the end
// of its flight; the HTTP clients' next GET of the old version is a 410, and they go on with the new
// version, ending on its local refinement. The two models are real .pms files of different terrains.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client/multilevel_client.h"
#include "client/multilevel_viewer.h"
#include "client/receiver_client.h"
#include "client/receiver_viewer.h"
#include "client/streaming_client.h"
#include "io/shapes.h"
#include "server/catalogue.h"
#include "server/catalogue_slot.h"
#include "server/http_server.h"
#include "server/tcp_server.h"
#include "common/error.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms::test {
namespace {

namespace fs = std::filesystem;

const Fixture& first() {
  static const Fixture f = make_fixture(make_terrain(8000, 1), "m");
  return f;
}

const Fixture& second() {
  static const Fixture f = make_fixture(make_terrain(12000, 2), "m");
  return f;
}

// DIR/m.pms served from a slot, first()'s file until replace() renames second()'s over it and reloads.
struct ReplacedModel {
  ReplacedModel() : dir(temp_dir()) {
    fs::copy_file(first().path, dir / "m.pms");
    slot = std::make_shared<server::CatalogueSlot>(server::Catalogue::open({dir.string()}));
    old_version = slot->get()->find("m")->version;
  }

  // As an operator replaces a served file: a new file renamed over it (the mapping of the old one stays
  // valid for the sessions that hold it).
  void replace() {
    fs::copy_file(second().path, dir / "m.pms.new");
    fs::rename(dir / "m.pms.new", dir / "m.pms");
    server::CatalogueChanges changes;
    slot->set(server::Catalogue::reload(*slot->get(), server::ServerLimits{}, changes));
    EXPECT_EQ(changes.replaced, std::vector<std::string>{"m"});
    EXPECT_TRUE(changes.added.empty() && changes.removed.empty() && changes.skipped.empty());
    EXPECT_NE(slot->get()->find("m")->version, old_version);
  }

  // An HTTP server over the slot, started: its port.
  uint16_t serve_http() {
    http = std::make_unique<server::HttpServer>(slot, server::HttpLimits{}, "127.0.0.1", 0);
    http->start();
    return http->port();
  }

  // A client that opened "m" over TCP, on a server over the slot started for the first.
  std::unique_ptr<client::StreamingClient> open_over_tcp() {
    if (!tcp) {
      tcp = std::make_unique<server::TcpServer>(slot, server::ServerLimits{}, "127.0.0.1", 0);
      tcp->start();
    }
    auto client = std::make_unique<client::StreamingClient>("127.0.0.1", tcp->port(), client::ClientOptions{1.0f});
    client->open("m");
    return client;
  }

  fs::path dir;
  std::shared_ptr<server::CatalogueSlot> slot;
  std::string old_version;
  std::unique_ptr<server::HttpServer> http;
  std::unique_ptr<server::TcpServer> tcp;
};

std::string http_url(uint16_t port) { return "http://127.0.0.1:" + std::to_string(port); }

TEST(ModelReplaced, ATcpSessionKeepsItsModelAndANewOneOpensTheNewFile) {
  ReplacedModel m;
  const auto client = m.open_over_tcp();
  const std::vector<Camera> path = orbit_path(first().hierarchy, 8, 0.3f);
  for (size_t i = 0; i < path.size(); ++i) {
    if (i == 3) m.replace();
    client->frame(path[i]);
    EXPECT_EQ(faces_by_id(client->session().mesh()), local_faces(first().snapped, path[i], 1.0f)) << "frame " << i;
  }
  const auto fresh = m.open_over_tcp();
  const Camera camera = orbit_path(second().hierarchy, 8, 0.3f).back();
  fresh->frame(camera);
  EXPECT_EQ(faces_by_id(fresh->session().mesh()), local_faces(second().snapped, camera, 1.0f));
}

// A reload that finds a file's content unchanged (even copied anew: another inode, the same bytes) keeps
// its model, mapping and built tables: nothing is built twice, no URL changes.
TEST(ModelReplaced, AnUnchangedFileKeepsItsModelAndItsTables) {
  ReplacedModel m;
  const server::ServedModel* before = m.slot->get()->find("m");
  m.slot->get()->table_builds().build_all({before}, server::ModeSet().set(server::index_of(server::ServedMode::receiver)));
  const uint64_t builds = m.slot->get()->table_builds().stats().started.load();
  fs::copy_file(first().path, m.dir / "m.pms.new");
  fs::rename(m.dir / "m.pms.new", m.dir / "m.pms");
  server::CatalogueChanges changes;
  m.slot->set(server::Catalogue::reload(*m.slot->get(), server::ServerLimits{}, changes));
  EXPECT_EQ(changes.kept, std::vector<std::string>{"m"});
  EXPECT_FALSE(changes.any());
  EXPECT_EQ(m.slot->get()->find("m"), before);
  EXPECT_TRUE(before->tables->ready(server::ServedMode::receiver));
  EXPECT_EQ(m.slot->get()->table_builds().stats().started.load(), builds) << "nothing built again";
}

// A session that loses its connection after the reload cannot resume its front on another file: it fails
// with an error that says so, never a mesh of both models.
TEST(ModelReplaced, AResumeOntoTheReplacedFileIsAClearError) {
  ReplacedModel m;
  const auto client = m.open_over_tcp();
  const std::vector<Camera> path = orbit_path(first().hierarchy, 8, 0.3f);
  for (size_t i = 0; i < 4; ++i) client->frame(path[i]);
  m.replace();
  try {
    client->resume("127.0.0.1", m.tcp->port());
    client->frame(path[4]);
    FAIL() << "resumed a front of the old file on the new one";
  } catch (const Error& e) {
    const std::string what = e.what();
    // The server finds an id of the old front missing from the new file, or the client a BASE not its own.
    EXPECT_TRUE(what.find("is not in the model") != std::string::npos ||
                what.find("not the one this client holds") != std::string::npos)
        << what;
  }
}

// Lock-step: the frame whose GET met the 410 is flown again on the new version, so every frame after the
// replacement that asked for anything shows the new model's local refinement.
TEST(ModelReplaced, AReceiverClientReopensOnTheNewVersionAndEndsOnItsRefinement) {
  for (const client::FetchPolicy fetch : {client::FetchPolicy::lists, client::FetchPolicy::blocks}) {
    ReplacedModel m;
    const uint16_t port = m.serve_http();
    client::ReceiverOptions options;
    options.fetch = fetch;
    client::ReceiverClient client(client::HttpUrl{"127.0.0.1", port, ""}, options);
    client.open("m");
    for (const Camera& camera : orbit_path(first().hierarchy, 8, 0.3f)) client.frame(camera);
    const uint64_t before = client.session().splits_received();
    m.replace();
    const std::vector<Camera> path = orbit_path(second().hierarchy, 8, 0.6f);
    for (const Camera& camera : path) {
      client.frame(camera);
      if (client.reopens() == 0) continue;
      EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(second().snapped, camera, 1.0f));
    }
    EXPECT_EQ(client.reopens(), 1u) << client::fetch_policy_name(fetch);
    EXPECT_GT(before, 0u);
    EXPECT_EQ(client.version(), m.slot->get()->find("m")->version) << "the new file's";
  }
}

// Free-running (the browser's pacing): the 410 drops the mesh, frames report opening until the new
// version is open, and settling ends on the new model's refinement.
TEST(ModelReplaced, AFreeRunningReceiverViewerFollowsTheNewVersion) {
  ReplacedModel m;
  const uint16_t port = m.serve_http();
  client::ReceiverViewer viewer(http_url(port), client::ReceiverOptions{}, client::Pacing::free_running, "m");
  for (const Camera& camera : orbit_path(first().hierarchy, 6, 0.3f)) viewer.frame(camera);
  m.replace();
  const std::vector<Camera> path = orbit_path(second().hierarchy, 8, 0.6f);
  // Frames never wait: they go on until one has met the 410 (a frame a millisecond, as a display would).
  client::ViewerReport met;
  for (int i = 0; i < 5000 && viewer.client().reopens() == 0; ++i) {
    met = viewer.frame(path[std::min<size_t>(i, path.size() - 1)]);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(viewer.client().version(), m.slot->get()->find("m")->version);
  EXPECT_TRUE(met.opening || met.faces > 0) << "nothing of the old version: the new one opening, or its mesh";
  for (const Camera& camera : path) viewer.frame(camera);
  viewer.settle(path.back());
  EXPECT_EQ(viewer.client().reopens(), 1u);
  EXPECT_EQ(faces_by_id(viewer.client().session().mesh()), local_faces(second().snapped, path.back(), 1.0f));
}

// The multilevel client: the levels of the old version are dropped on the 410, the new version's load,
// and the LOD it settles on is a fresh client's of the new file, in either pacing.
TEST(ModelReplaced, AMultilevelClientReloadsTheNewVersionsLevels) {
  for (const client::Pacing pacing : {client::Pacing::lock_step, client::Pacing::free_running}) {
    ReplacedModel m;
    const uint16_t port = m.serve_http();
    client::MultilevelOptions options;
    options.morph_frames = 4;
    options.budget = 1;  // the coarsest level alone, until the replacement
    client::MultilevelViewer viewer(http_url(port), options, pacing, "m");
    viewer.frame(orbit_path(first().hierarchy, 8, 0.3f).front());
    m.replace();
    client::ViewerTuning finest;
    finest.lod_budget = uint64_t(1) << 40;
    viewer.retune(finest);
    const std::vector<Camera> path = orbit_path(second().hierarchy, 8, 0.6f);
    for (const Camera& camera : path) viewer.frame(camera);
    viewer.settle(path.back());
    EXPECT_EQ(viewer.client().reopens(), 1u) << "the first finer level's GET met the 410";
    options.budget = *finest.lod_budget;
    client::MultilevelClient fresh(client::HttpUrl{"127.0.0.1", port, ""}, options);
    fresh.open("m");
    fresh.settle(path.back());
    EXPECT_EQ(viewer.client().loader().level_count(), fresh.loader().level_count());
    const Mesh got = viewer.client().current_mesh(), want = fresh.current_mesh();
    EXPECT_EQ(got.positions, want.positions);
    EXPECT_EQ(got.indices, want.indices);
  }
}

}  // namespace
}  // namespace pms::test
