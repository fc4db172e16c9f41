// The WASM module's C API (docs/architecture.md, "Browser build"): the browser's viewers
// (client/message_session_viewer.h, the receiver and multilevel viewers over
// client/external_http_transport.h) behind plain functions that web/js/pmstream.js calls. Nothing here
// blocks: JS moves the bytes (WebSocket messages, fetch answers) in and out, and frames.
//
// Conventions: a viewer is a handle (> 0); a call that fails returns 0 (or a null pointer) and leaves its
// message for pms_last_error(). Strings and JSON come back in a buffer valid until the next call that
// returns one; pointers into the viewer's buffers until the next call into that viewer.
// Only em++ compiles this file (web/CMakeLists.txt).
#include <emscripten/emscripten.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "client/external_http_transport.h"
#include "client/face_id_importance.h"
#include "client/message_session_viewer.h"
#include "client/multilevel_viewer.h"
#include "client/receiver_viewer.h"
#include "client/viewer.h"
#include "common/camera.h"
#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/stream_mode.h"
#include "web/view_probe.h"

namespace pms::web {
namespace {

using nlohmann::json;

// One page viewer: the Viewer and, for its mode, the pieces JS talks to (owned by the viewer).
struct PageViewer {
  std::unique_ptr<client::Viewer> viewer;
  client::MessageSessionViewer* session = nullptr;  // sender, sender-plain, vi, dag
  client::ExternalHttpTransport* http = nullptr;    // receiver, multilevel
  client::FaceIdImportance* face_ids = nullptr;     // receiver
  client::ReceiverViewer* receiver = nullptr;
  client::ViewerReport last;
  std::vector<uint8_t> outgoing;  // frames to send, concatenated (each carries its length)
  uint32_t buffer_table[10] = {};
  Mesh mesh;  // pms_viewer_mesh's copy
  uint32_t mesh_table[4] = {};
};

std::map<int, std::unique_ptr<PageViewer>> viewers;
int next_handle = 1;
std::string last_error;
std::string text_out;  // the last JSON or string handed out

const char* hand_out(std::string text) {
  text_out = std::move(text);
  return text_out.c_str();
}

// Runs `body`; an exception becomes last_error and `failed`.
template <class Body, class Result>
Result guarded(Body&& body, Result failed) {
  try {
    return body();
  } catch (const std::exception& e) {
    last_error = e.what();
  } catch (...) {
    last_error = "unknown error";
  }
  return failed;
}

PageViewer& viewer_of(int handle) {
  const auto it = viewers.find(handle);
  if (it == viewers.end()) fail("viewer", "no viewer " + std::to_string(handle));
  return *it->second;
}

DagTraversal traversal_named(const std::string& name) {
  const std::optional<DagTraversal> traversal = protocol::dag_traversal_named(name);
  if (!traversal) fail("dag.traversal", "'" + name + "': " + protocol::kDagTraversalNames);
  return *traversal;
}

// dag.maxOps: 0 is the paper's N, as `pmstream stream --max-ops 0`.
uint32_t max_ops_of(const json& dag) {
  const uint32_t max_ops = dag.value("maxOps", 0u);
  return max_ops ? max_ops : 300;
}

protocol::DagView dag_request(const json& dag, float tolerance) {
  protocol::DagView request;
  request.traversal = traversal_named(dag.value("traversal", "priority"));
  request.budget = dag.value("budget", uint64_t(0));
  request.management = request.budget ? DagMode::budget : DagMode::free;
  request.max_ops = max_ops_of(dag);
  request.view.tolerance = tolerance;
  return request;
}

// pms_viewer_set's JSON: only the options it names.
client::ViewerTuning tuning_of(const json& o) {
  client::ViewerTuning t;
  if (o.contains("tolerance")) t.tolerance = o["tolerance"].get<float>();
  if (o.contains("morphFrames")) t.morph_frames = o["morphFrames"].get<uint32_t>();
  if (const auto dag = o.find("dag"); dag != o.end() && dag->is_object()) {
    if (dag->contains("traversal")) t.dag_traversal = traversal_named((*dag)["traversal"].get<std::string>());
    if (dag->contains("budget")) t.dag_budget = (*dag)["budget"].get<uint64_t>();
    if (dag->contains("maxOps")) t.dag_max_ops = max_ops_of(*dag);
  }
  if (const auto r = o.find("receiver"); r != o.end() && r->is_object()) {
    if (r->contains("fetch")) fail("receiver.fetch", "changes only with a new viewer");
    if (r->contains("prefetch")) t.prefetch = (*r)["prefetch"].get<bool>();
    if (r->contains("background")) t.background_bytes = (*r)["background"].get<uint64_t>();
  }
  if (const auto m = o.find("multilevel"); m != o.end() && m->is_object() && m->contains("budget"))
    t.lod_budget = (*m)["budget"].get<uint64_t>();
  for (const char* fixed : {"mode", "model"})
    if (o.contains(fixed)) fail(fixed, "changes only with a new viewer");
  return t;
}

// A time budget given in milliseconds, as microseconds; absent: 0 (no limit).
uint32_t budget_us(const json& o, const char* key) {
  if (!o.contains(key)) return 0;
  const double ms = o[key].get<double>();
  if (!(ms >= 0 && ms <= 60000)) fail(key, "must be a number of milliseconds in [0, 60000]");
  return uint32_t(ms * 1000);
}

std::unique_ptr<PageViewer> make_viewer(const json& o) {
  auto page = std::make_unique<PageViewer>();
  const std::string mode = o.value("mode", "sender");
  const std::string model = o.value("model", "");
  if (model.empty()) fail("open", "no model named");
  const float tolerance = o.value("tolerance", 1.0f);
  const uint32_t morph = o.value("morphFrames", client::kDefaultGeomorphFrames);
  const uint32_t in_flight = o.value("inFlight", 4u);
  const uint32_t adapt_budget_us = budget_us(o, "adaptBudgetMs");
  if (mode == "receiver") {
    const json r = o.value("receiver", json::object());
    client::ReceiverOptions options;
    options.tolerance = tolerance;
    options.morph_frames = morph;
    options.fetch = client::fetch_policy_named(r.value("fetch", "lists"), "receiver.fetch");
    options.prefetch = r.value("prefetch", false);
    options.background_bytes = r.value("background", uint64_t(0));
    options.adapt_budget_us = adapt_budget_us;
    auto http = std::make_unique<client::ExternalHttpTransport>(in_flight);
    auto face_ids = std::make_unique<client::FaceIdImportance>();
    page->http = http.get();
    page->face_ids = face_ids.get();
    auto viewer = std::make_unique<client::ReceiverViewer>(std::move(http), std::move(face_ids), options, model);
    page->receiver = viewer.get();
    page->viewer = std::move(viewer);
    return page;
  }
  if (mode == "multilevel") {
    client::MultilevelOptions options;
    options.tolerance = tolerance;
    options.morph_frames = morph;
    options.budget = o.value("multilevel", json::object()).value("budget", uint64_t(0));
    auto http = std::make_unique<client::ExternalHttpTransport>(in_flight);
    page->http = http.get();
    page->viewer = std::make_unique<client::MultilevelViewer>(std::move(http), options, model);
    return page;
  }
  const std::optional<protocol::StreamMode> wire = protocol::mode_named(mode);
  if (!wire) fail("mode", "'" + mode + "': " + client::viewer_mode_names());
  client::ClientOptions options;
  options.tolerance = tolerance;
  options.mode = *wire;
  // The other session modes make splits as they come (or as the server's cut says): nothing to blend.
  options.morph_frames = *wire == protocol::StreamMode::sender_driven ? morph : 0;
  options.dag = dag_request(o.value("dag", json::object()), tolerance);
  options.name = "pmstream-web";
  options.adapt_budget_us = adapt_budget_us;
  if (o.contains("applyBudgetMs")) {
    options.apply_budget = std::chrono::microseconds(budget_us(o, "applyBudgetMs"));
    if (options.apply_budget.count() == 0) fail("applyBudgetMs", "must be more than 0");
  }
  auto viewer = std::make_unique<client::MessageSessionViewer>(options, model);
  page->session = viewer.get();
  page->viewer = std::move(viewer);
  return page;
}

bool settled(const PageViewer& page) {
  if (page.session) return page.session->settled();
  return !page.last.opening && page.last.satisfied && page.last.in_flight == 0 && page.http->pending() == 0 &&
         !page.viewer->in_motion();
}

json report_json(const PageViewer& page, const client::ViewerReport& r) {
  const client::Viewer& v = *page.viewer;
  json out = {{"frame", r.frame},
              {"faces", r.faces},
              {"vertices", r.vertices},
              {"received", r.received},
              {"receivedUnit", r.opening ? "" : v.received_unit()},
              {"receivedTotal", r.opening ? 0 : v.received_total()},
              {"upBytes", v.up_bytes()},
              {"downBytes", v.down_bytes()},
              {"latencyMs", r.latency_ms},
              {"inFlight", r.in_flight},
              {"satisfied", r.satisfied},
              {"opening", r.opening},
              {"settled", settled(page)},
              {"refused", r.refused},
              {"details", r.details.is_null() ? json::object() : r.details}};
  if (!page.session && !page.receiver && !r.opening && r.details.is_object())
    out["levels"] = {{"loaded", r.details.value("levels_loaded", 0u)},
                     {"shown", r.details.value("level", 0.0f)},
                     {"count", v.totals().value("levels", 0u)}};
  return out;
}

}  // namespace
}  // namespace pms::web

using namespace pms;
using namespace pms::web;

extern "C" {

EMSCRIPTEN_KEEPALIVE const char* pms_last_error() { return last_error.c_str(); }

// Bytes for JS to fill (a fetch answer, a WebSocket message, a face-id frame); freed by pms_free.
EMSCRIPTEN_KEEPALIVE uint8_t* pms_alloc(uint32_t size) { return new (std::nothrow) uint8_t[size ? size : 1]; }
EMSCRIPTEN_KEEPALIVE void pms_free(uint8_t* bytes) { delete[] bytes; }

// `options_json`: {mode, model, tolerance, morphFrames, inFlight, dag: {traversal, budget, maxOps},
// receiver: {fetch, prefetch, background (the idle fetch's bytes)}, multilevel: {budget}}. The viewer's
// handle, or 0.
EMSCRIPTEN_KEEPALIVE int pms_viewer_open(const char* options_json) {
  return guarded(
      [&] {
        const json options = json::parse(options_json);
        viewers[next_handle] = make_viewer(options);
        return next_handle++;
      },
      0);
}

EMSCRIPTEN_KEEPALIVE void pms_viewer_close(int handle) { viewers.erase(handle); }

// Options changed on the open viewer, the mesh kept (client::Viewer::tune): `options_json` names any of
// tolerance, morphFrames, dag: {traversal, budget, maxOps}, receiver: {prefetch, background}, multilevel: {budget}.
// 1, or 0 with nothing changed (a value out of range, or mode, model or receiver.fetch named: those need
// a new viewer).
EMSCRIPTEN_KEEPALIVE int pms_viewer_set(int handle, const char* options_json) {
  return guarded(
      [&] {
        PageViewer& page = viewer_of(handle);
        page.viewer->tune(tuning_of(json::parse(options_json)));
        return 1;
      },
      0);
}

// `camera`: eye (3), target (3), up (3), fovy in degrees. The frame's report as JSON, or null.
EMSCRIPTEN_KEEPALIVE const char* pms_viewer_frame(int handle, const float* camera, uint32_t width, uint32_t height) {
  return guarded(
      [&]() -> const char* {
        PageViewer& page = viewer_of(handle);
        page.last = page.viewer->frame(camera_of(camera, width, height));
        return hand_out(report_json(page, page.last).dump());
      },
      static_cast<const char*>(nullptr));
}

EMSCRIPTEN_KEEPALIVE int pms_viewer_settled(int handle) {
  return guarded([&] { return int(settled(viewer_of(handle))); }, 0);
}

EMSCRIPTEN_KEEPALIVE const char* pms_viewer_totals(int handle) {
  return guarded([&]() -> const char* { return hand_out(viewer_of(handle).viewer->totals().dump()); },
                 static_cast<const char*>(nullptr));
}

// The buffers brought up to date: 10 u32 = positions, normals, colors, indices (pointers), vertex count,
// triangle count, then the changed vertex and triangle ranges as pointers to (first, count) pairs and
// their counts.
EMSCRIPTEN_KEEPALIVE const uint32_t* pms_viewer_buffers(int handle) {
  return guarded(
      [&]() -> const uint32_t* {
        PageViewer& page = viewer_of(handle);
        const client::MeshBuffers& b = page.viewer->buffers();
        uint32_t* t = page.buffer_table;
        t[0] = uint32_t(reinterpret_cast<uintptr_t>(b.positions.data()));
        t[1] = uint32_t(reinterpret_cast<uintptr_t>(b.normals.data()));
        t[2] = uint32_t(reinterpret_cast<uintptr_t>(b.colors.data()));
        t[3] = uint32_t(reinterpret_cast<uintptr_t>(b.indices.data()));
        t[4] = b.vertex_count();
        t[5] = b.triangle_count();
        static_assert(sizeof(client::BufferRange) == 8);
        t[6] = uint32_t(reinterpret_cast<uintptr_t>(b.changed_vertices.data()));
        t[7] = uint32_t(b.changed_vertices.size());
        t[8] = uint32_t(reinterpret_cast<uintptr_t>(b.changed_triangles.data()));
        t[9] = uint32_t(b.changed_triangles.size());
        return t;
      },
      static_cast<const uint32_t*>(nullptr));
}

// The mesh now, copied: 4 u32 = positions pointer, vertex count, faces pointer, face count.
EMSCRIPTEN_KEEPALIVE const uint32_t* pms_viewer_mesh(int handle) {
  return guarded(
      [&]() -> const uint32_t* {
        PageViewer& page = viewer_of(handle);
        page.mesh = page.viewer->mesh();
        page.mesh_table[0] = uint32_t(reinterpret_cast<uintptr_t>(page.mesh.positions.data()));
        page.mesh_table[1] = uint32_t(page.mesh.positions.size() / 3);
        page.mesh_table[2] = uint32_t(reinterpret_cast<uintptr_t>(page.mesh.indices.data()));
        page.mesh_table[3] = uint32_t(page.mesh.indices.size() / 3);
        return page.mesh_table;
      },
      static_cast<const uint32_t*>(nullptr));
}

// The model's box as JSON {min, max} once open (the BASE's, or the multilevel mesh's), else null.
EMSCRIPTEN_KEEPALIVE const char* pms_viewer_bounds(int handle) {
  return guarded(
      [&]() -> const char* {
        PageViewer& page = viewer_of(handle);
        client::ClientSession* session = page.session    ? &page.session->session()
                                         : page.receiver ? &page.receiver->client().session()
                                                         : nullptr;
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        if (session) {
          if (!session->has_model()) return nullptr;
          for (int k = 0; k < 3; ++k) lo[k] = session->base().bbox_min[k], hi[k] = session->base().bbox_max[k];
        } else {
          const Mesh mesh = page.viewer->mesh();
          if (mesh.positions.empty()) return nullptr;
          for (size_t i = 0; i < mesh.positions.size(); ++i) {
            lo[i % 3] = std::min(lo[i % 3], mesh.positions[i]);
            hi[i % 3] = std::max(hi[i % 3], mesh.positions[i]);
          }
        }
        return hand_out(json{{"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}}.dump());
      },
      static_cast<const char*>(nullptr));
}

// ---- the session modes' socket ----

EMSCRIPTEN_KEEPALIVE int pms_session_connected(int handle) {
  return guarded([&] { return (viewer_of(handle).session->connected(), 1); }, 0);
}
EMSCRIPTEN_KEEPALIVE int pms_session_disconnected(int handle) {
  return guarded([&] { return (viewer_of(handle).session->disconnected(), 1); }, 0);
}
// One WebSocket message (or any chunk of the TCP stream).
EMSCRIPTEN_KEEPALIVE int pms_session_bytes(int handle, const uint8_t* bytes, uint32_t size) {
  return guarded([&] { return (viewer_of(handle).session->on_bytes({bytes, size}), 1); }, 0);
}
// The frames to send, concatenated (each starts with its u32 length and type byte); `size` gets their bytes.
EMSCRIPTEN_KEEPALIVE const uint8_t* pms_session_outgoing(int handle, uint32_t* size) {
  return guarded(
      [&]() -> const uint8_t* {
        PageViewer& page = viewer_of(handle);
        page.outgoing.clear();
        for (const std::vector<uint8_t>& frame : page.session->take_outgoing())
          page.outgoing.insert(page.outgoing.end(), frame.begin(), frame.end());
        *size = uint32_t(page.outgoing.size());
        return page.outgoing.data();
      },
      static_cast<const uint8_t*>(nullptr));
}

// ---- the HTTP modes' fetches ----

// The GETs to fetch now: JSON [[id, target], ...] (targets under the server's URL).
EMSCRIPTEN_KEEPALIVE const char* pms_http_gets(int handle) {
  return guarded(
      [&]() -> const char* {
        json out = json::array();
        for (const client::ExternalHttpTransport::Get& get : viewer_of(handle).http->take_gets())
          out.push_back({get.id, get.target});
        return hand_out(out.dump());
      },
      static_cast<const char*>(nullptr));
}
EMSCRIPTEN_KEEPALIVE int pms_http_deliver(int handle, uint32_t id, int status, const uint8_t* body, uint32_t size,
                                          double wire_bytes) {
  return guarded(
      [&] {
        viewer_of(handle).http->deliver(id, status, std::vector<uint8_t>(body, body + size), uint64_t(wire_bytes));
        return 1;
      },
      0);
}
EMSCRIPTEN_KEEPALIVE int pms_http_fail(int handle, uint32_t id, const char* reason) {
  return guarded([&] { return (viewer_of(handle).http->fail_get(id, reason), 1); }, 0);
}

// ---- the receiver's face-id frame ----

EMSCRIPTEN_KEEPALIVE int pms_viewer_face_ids(int handle, const uint8_t* rgba, uint32_t width, uint32_t height) {
  return guarded(
      [&] {
        PageViewer& page = viewer_of(handle);
        if (!page.face_ids) fail("face ids", "only the receiver mode ranks by a face-id frame");
        page.face_ids->set_face_ids({rgba, size_t(width) * height * 4}, width, height);
        return 1;
      },
      0);
}

// ---- the view math, for the test that compares it with the native build's bit for bit ----

// `count` cases of web/view_probe.h: kProbeInputs floats each in, kProbeOutputs out.
EMSCRIPTEN_KEEPALIVE void pms_probe_view_math(const float* in, float* out, uint32_t count) {
  for (uint32_t i = 0; i < count; ++i) probe_view_math(in + i * kProbeInputs, out + i * kProbeOutputs);
}

}  // extern "C"
