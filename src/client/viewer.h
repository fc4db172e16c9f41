// One viewer for every streaming mode (docs/architecture.md, "Viewer"): open a model in a mode with that
// mode's options, then frame(camera) per displayed frame. The six modes (sender, sender-plain, vi, dag over
// the TCP session protocol; receiver and multilevel over HTTP) sit behind this one interface, so the
// headless viewer, the demo, the tests and the bench drive them alike.
//
// Two pacings:
// - lock_step: frame() runs until the view is satisfied (what the mode's server sends for it has arrived
//   and been applied), so every property the tests rely on holds after every frame: the mesh equals local
//   refinement for sender and receiver, a second lap costs 0 bytes, the DAG cut is mirrored.
// - free_running: frame() applies what has arrived, asks for what the view lacks, and returns without
//   waiting for the network; settle() then waits until the last view is satisfied, and the same
//   properties hold after it.
#pragma once
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "client/mesh_buffers.h"
#include "client/multilevel_client.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "common/camera.h"
#include "io/mesh.h"
#include "spm/adapt.h"
#include "spm/selective_mesh.h"

namespace pms::client {

enum class Pacing : uint8_t { lock_step, free_running };

// Frames a split or a collapse (a LOD switch for multilevel) is blended over by default in the modes that
// have geomorphs (sender, receiver, multilevel): on, so that a viewer does not pop, and short, so that
// what arrives shows within a quarter of a second at 30 fps.
constexpr uint32_t kDefaultGeomorphFrames = 8;

struct ViewerOptions {
  ViewerOptions() { session.morph_frames = receiver.morph_frames = multilevel.morph_frames = kDefaultGeomorphFrames; }

  std::string mode = "sender";  // sender, sender-plain, vi, dag, receiver, multilevel
  // HOST:PORT of the TCP port (session modes), http://HOST:PORT[/prefix] of the HTTP port (the others).
  std::string server;
  Pacing pacing = Pacing::lock_step;
  ClientOptions session;          // sender, sender-plain, vi, dag (its mode field is set from `mode`)
  ReceiverOptions receiver;       // receiver
  MultilevelOptions multilevel;   // multilevel
};

// One frame as the viewer saw it.
struct ViewerReport {
  uint32_t frame = 0;
  uint64_t faces = 0;
  uint64_t vertices = 0;
  uint64_t received = 0;  // splits this frame, or levels for multilevel (received_unit says which)
  uint64_t up_bytes = 0, down_bytes = 0;  // this frame's traffic, on the wire
  uint32_t in_flight = 0;  // requests sent and not yet answered at the frame's end
  double latency_ms = 0;   // request -> last of its answer applied, for the last answer applied this frame
  bool satisfied = true;   // the view wants nothing more that the server has
  bool opening = false;    // the event-driven viewers (the browser's): no model yet, the frame did nothing
  // Non-empty: the camera was degenerate (camera_problem says how) and the frame did nothing; the mesh and
  // everything else stay as the last frame left them, and the next good camera goes on from there.
  std::string refused;
  nlohmann::json details;  // the mode's own per-frame counters (docs/cli.md, "stream")
};

// The options an open viewer lets change without reopening it (Viewer::tune): each one set replaces that
// option and the mesh is kept; a mode ignores what it does not have, as open_viewer does. The model, the
// mode and the receiver's fetch style need a new viewer.
struct ViewerTuning {
  std::optional<float> tolerance;
  std::optional<uint32_t> morph_frames;  // the modes with geomorphs (sender, receiver, multilevel)
  std::optional<DagTraversal> dag_traversal;
  std::optional<uint64_t> dag_budget;   // > 0: the budget variant of the traversal
  std::optional<uint32_t> dag_max_ops;  // 1 .. protocol::kMaxDagOps
  std::optional<bool> prefetch;         // receiver
  std::optional<uint64_t> background_bytes;  // receiver: the idle fetch's budget, 0 = off (free-running only)
  std::optional<uint64_t> lod_budget;   // multilevel: > 0 a fixed LOD by triangles, 0 the screen-size rule
};

// What an event-driven viewer's frame reports while its model is still opening.
ViewerReport opening_report();

class Viewer {
 public:
  virtual ~Viewer() = default;
  // One displayed frame at `camera`; a degenerate camera (eye == target, up zero or along the view, not
  // finite, an empty viewport) is refused: the report says why and repeats the last frame's state.
  ViewerReport frame(const Camera& camera);
  // Holds `camera` until its view is satisfied and nothing is still in motion (geomorphs, answers in
  // flight): the mesh is then what lock_step gives at that camera.
  virtual void settle(const Camera& camera) = 0;
  virtual Mesh mesh() const = 0;                                // as it is now
  virtual ViewParams view_params(const Camera& camera) const = 0;  // the mode's view of `camera`
  virtual const char* received_unit() const = 0;                // "vsplits" or "levels"
  virtual uint64_t received_total() const = 0;
  virtual uint64_t up_bytes() const = 0;    // in total, on the wire
  virtual uint64_t down_bytes() const = 0;  // in total, on the wire
  virtual nlohmann::json totals() const = 0;  // the mode's own totals (docs/cli.md, "stream")
  // New options now (ViewerTuning); the next frame uses them. pms::Error naming the option for a value out
  // of range (nothing is changed then), or for a viewer whose options are fixed.
  void tune(const ViewerTuning& tuning);
  // Geomorphs still moving, or the last adaptation operated or stopped at its cap (the next walk may find
  // more to do): a frame would change the mesh with nothing new arriving.
  virtual bool in_motion() const;

  // The mesh as a renderer's buffers (mesh_buffers.h), brought up to date now: what changed since the call
  // before is in their changed ranges. Costs a read of every face slot and active vertex; a headless run
  // never calls it.
  const MeshBuffers& buffers();

 protected:
  virtual ViewerReport frame_view(const Camera& camera) = 0;  // frame() at a camera make_view takes
  virtual void retune(const ViewerTuning& tuning);              // tune() with its values checked
  // What the session modes and the receiver-driven mode show; null for a mode whose mesh() is numbered
  // its own way (multilevel's LOD).
  virtual const SelectiveRefinement* refinement() const { return nullptr; }

 private:
  MeshBuffers buffers_;
  ViewerReport last_ = opening_report();  // what a refused frame repeats: before any, nothing shown yet
};

// Connects and opens `model` on `options.server` in `options.mode`. pms::Error for an unknown mode (naming
// --mode) or a server that cannot be reached or refuses the model.
std::unique_ptr<Viewer> open_viewer(const ViewerOptions& options, const std::string& model);

// A refined mesh's flat arrays as io's Mesh (what the exporters and the renderer take).
Mesh to_mesh(MeshArrays&& arrays);
// The mesh `refinement` holds now.
Mesh current_mesh(const SelectiveRefinement& refinement);

// "sender, sender-plain, vi, dag, receiver, multilevel".
std::string viewer_mode_names();

}  // namespace pms::client
