// The multilevel client (gueziec et al. 1999, progressive loading; docs/protocol.md, "Multilevel over
// HTTP"): the model's entry and head in one round trip, then its levels coarsest first (compressed unless
// asked otherwise), each added to the structure as it arrives (MultilevelLoader::add_level) and usable at
// once; every frame picks a LOD by a triangle budget or a screen-size rule among the levels loaded and
// switches to it with setLevel (a geomorph over --geomorph-frames). Free-running, the levels load in the
// background and no frame waits for one. No session, like the receiver-driven client: a driver of its own
// over an HttpTransport, with no I/O of its own (answers in, targets out).
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "client/client_mode.h"
#include "client/http_transport.h"
#include "client/model_version.h"
#include "common/camera.h"
#include "io/mesh.h"
#include "multilevel/loader.h"
#include "multilevel/mesh.h"

namespace pms::client {

struct MultilevelOptions {
  uint64_t budget = 0;        // > 0: the finest LOD of at most this many triangles; 0: the screen-size rule
  float tolerance = 1;        // screen-size rule: the coarsest LOD whose error covers at most this many pixels
  uint32_t morph_frames = 0;  // a LOD switch is one geomorph over this many frames, however far; 0 = at once
  bool compressed = true;     // the compressed levels (positions on the server's grid), or the binary form's
  HttpOptions http;  // the HttpConnection made from a URL
  MultilevelLimits limits;  // what the head may announce
  // frame() never waits for a level: open() brings the coarsest with the head, and each frame adds the
  // levels fully arrived, asks (pipelined, coarsest first) for those the rule wants, and shows the finest
  // loaded within the rule. settle() waits for the last camera's level: then the mesh is lock-step's.
  bool free_running = false;
};

// When a level became usable: counted from the start of open().
struct LevelArrival {
  uint32_t level = 0;
  uint64_t bytes = 0;         // its body
  uint64_t down_bytes = 0;    // everything received on the wire by then (catalogue and head included)
  uint64_t payload_down = 0;  // the bodies alone
  double ms = 0;
};

struct MultilevelFrame {
  FrameReport report;  // up/down bytes on the wire; vsplits: levels received this frame
  uint64_t payload_down = 0;
  uint32_t wanted_level = 0;  // what the rule asks for
  float level = 0;            // what is shown (fractional during a geomorph)
  uint32_t levels_loaded = 0;
  uint32_t in_flight = 0;  // level GETs sent and not yet added (free-running)
  double lod_ms = 0;       // setLevel for this frame
};

class MultilevelClient {
 public:
  // Over `http` (the native HttpConnection, the browser's fetch, a test's).
  MultilevelClient(std::unique_ptr<HttpTransport> http, const MultilevelOptions& options = {});
  // Over an HttpConnection to `server` with options.http (native builds: native_http_clients.cpp).
  MultilevelClient(const HttpUrl& server, const MultilevelOptions& options = {});

  std::vector<std::string> list();  // GET /models: the multilevel models' names
  // GET /models for the model's version, then its /multilevel entry and /head pipelined, and free-running
  // the coarsest level too (docs/protocol.md, "Versions"). A 410 later (the model replaced under its name)
  // drops the levels and opens the version it names, as the receiver-driven client does.
  void open(const std::string& model);
  // The same without waiting (the browser's): start_open() posts the GETs, each poll_open() takes what has
  // arrived, until it returns true: the model is open. frame() is for after that.
  void start_open(const std::string& model);
  bool poll_open();

  bool opened() const { return loader_.has_value(); }
  MultilevelFrame frame(const Camera& camera);
  void settle(const Camera& camera);  // the last camera's LOD loaded and reached, no geomorph left
  // A LOD switch still blending, or the last frame's target not yet shown: a frame would change the mesh
  // with nothing new arriving.
  bool in_motion() const;

  // New rule and geomorph length: the next frame picks its LOD by them (a switch under way finishes).
  void set_rule(float tolerance, uint64_t budget, uint32_t morph_frames);

  uint32_t wanted_level(const Camera& camera) const;
  ViewParams view_params(const Camera& camera) const;
  const MultilevelMesh& mesh() const { return loader_->mesh(); }
  const MultilevelLoader& loader() const { return *loader_; }
  const MultilevelLod& lod() const { return *lod_; }
  Mesh current_mesh() const { return lod_mesh(mesh(), *lod_); }
  const std::vector<LevelArrival>& arrivals() const { return arrivals_; }
  const HttpCounters& counters() const { return http_->counters(); }
  uint64_t reopens() const { return reopens_.total(); }  // versions opened after a 410

 private:
  std::string prefix(bool compressed) const;
  void open_version(const nlohmann::json& entry);
  void await_open();
  void replaced(const std::string& target, const HttpAnswer& answer);
  void opened(const std::vector<std::string>& targets, const std::vector<HttpAnswer>& answers);
  void read_entry(const std::string& model, const std::string& target, const HttpAnswer& answer);
  bool add(const std::string& target, const HttpAnswer& answer);
  uint32_t load_to(uint32_t level);
  uint32_t add_arrived(MultilevelFrame& out);
  void request_to(uint32_t level);
  void settle_free(uint32_t wanted);
  void show(float level, MultilevelFrame& out);
  void show_switch(MultilevelFrame& out);
  void step_to(uint32_t wanted, MultilevelFrame& out);

  // A LOD switch under way: a geomorph from LOD `from` to LOD `to`, `frame` of morph_frames done.
  struct LodSwitch {
    uint32_t from = 0, to = 0;
    uint32_t frame = 0;
  };

  MultilevelOptions options_;
  std::unique_ptr<HttpTransport> http_;
  std::string model_;
  std::string version_;  // the version open, or opening
  // The GETs of an open (GET /models alone, then a version's entry and head), until poll_open() has them.
  std::unique_ptr<PendingGets> opening_;
  ReopenBudget reopens_;
  std::chrono::steady_clock::time_point opened_;
  std::vector<uint32_t> lod_triangles_;  // per level (0 finest), from the catalogue
  std::vector<float> level_errors_;
  float center_[3] = {0, 0, 0}, radius_ = 1;
  std::optional<MultilevelLoader> loader_;
  std::optional<MultilevelLod> lod_;
  std::vector<LevelArrival> arrivals_;
  std::deque<std::string> posted_;  // free-running: level GETs on the wire, coarsest first
  uint32_t requested_ = 0;          // free-running: the finest level asked for (loaded or on the wire)
  float shown_ = -1;
  uint32_t target_ = 0;  // the last frame's: the level its camera wants, or the finest loaded if coarser
  std::optional<LodSwitch> switch_;
  uint32_t frame_ = 0;
};

}  // namespace pms::client
