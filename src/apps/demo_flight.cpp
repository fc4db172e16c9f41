// kim-lee-kobbelt §3's flight-simulator scene, end to end: server and client in one process, talking
// over real loopback TCP, exactly as `serve` and `stream` would over a network.
#include "apps/demo_flight.h"

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "apps/demo_views.h"
#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "client/transport.h"
#include "client/viewer.h"
#include "common/error.h"
#include "protocol/client_messages.h"
#include "render/render.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"

namespace pms::app {
namespace {

void snapshot(const client::Viewer& viewer, const Camera& camera, const std::string& path, Renderer& renderer,
              const RenderOptions& look, Image& image) {
  const Mesh mesh = viewer.mesh();
  renderer.render({mesh.positions, mesh.indices, mesh.colors}, viewer.view_params(camera), image, look);
  save_png(path, image);
}

// A lock-step viewer of `mode` on the in-process server.
std::unique_ptr<client::Viewer> open_demo_viewer(uint16_t port, const std::string& model_name, const char* mode,
                                                 float tolerance) {
  client::ViewerOptions options;
  options.mode = mode;
  options.server = "127.0.0.1:" + std::to_string(port);
  options.session.tolerance = tolerance;
  return client::open_viewer(options, model_name);
}

// kim-lee-kobbelt §8's baseline: the same flight in view-independent mode, where the server sends the plain
// PM order until each view is satisfied. Returns its bytes down.
uint64_t view_independent_bytes(uint16_t port, const std::string& model_name, const std::vector<Camera>& path,
                                float tolerance) {
  const std::unique_ptr<client::Viewer> viewer = open_demo_viewer(port, model_name, "vi", tolerance);
  for (const Camera& camera : path) viewer->frame(camera);
  return viewer->down_bytes();
}

struct Flight {
  std::vector<double> latencies;  // of the frames that sent a VIEW
  uint64_t face_sum = 0, requests = 0;
  double seconds = 0;
};

// A live line on a terminal; a line per snapshot interval in a log.
void print_progress(const client::Viewer& viewer, const client::ViewerReport& r, size_t frame, size_t frames,
                    bool interactive) {
  std::printf("%sflight:    frame %3zu/%zu  faces %7llu  vsplits %8llu  down %9llu B  up %7llu B%s",
              interactive ? "\r" : "", frame + 1, frames, (unsigned long long)r.faces,
              (unsigned long long)viewer.received_total(), (unsigned long long)viewer.down_bytes(),
              (unsigned long long)viewer.up_bytes(), interactive ? "" : "\n");
  std::fflush(stdout);
}

Flight fly(client::Viewer& viewer, const std::vector<Camera>& path, const FlightOptions& options,
           const RenderOptions& look, const std::string& snapshots) {
  Renderer renderer;
  Image image;
  Flight flight;
  Stopwatch clock;
  const bool interactive = isatty(fileno(stdout));
  for (size_t i = 0; i < path.size(); ++i) {
    const client::ViewerReport r = viewer.frame(path[i]);
    flight.face_sum += r.faces;
    if (r.latency_ms > 0) {  // it sent a VIEW
      flight.latencies.push_back(r.latency_ms);
      ++flight.requests;
    }
    const bool snapshot_frame = options.snapshot_every && (i % options.snapshot_every == 0 || i + 1 == path.size());
    if (interactive || snapshot_frame) print_progress(viewer, r, i, path.size(), interactive);
    if (snapshot_frame) {
      char name[64];
      std::snprintf(name, sizeof name, "/frame_%04zu.png", i);
      snapshot(viewer, path[i], snapshots + name, renderer, look, image);
    }
  }
  flight.seconds = clock.seconds();
  if (interactive) std::printf("\n");
  return flight;
}

std::string summary_table(const client::Viewer& viewer, const Flight& flight, size_t frames, uint64_t base_bytes,
                          uint64_t all_splits, uint64_t vi_bytes) {
  const double share = all_splits ? double(viewer.received_total()) / double(all_splits) : 0;
  const uint64_t faces = viewer.mesh().indices.size() / 3;
  char table[2048];
  std::snprintf(
      table, sizeof table,
      "| frames | faces (last / mean) | vsplits received | bytes down | bytes up | VIEW requests | latency p50 / p99 "
      "| view-independent bytes down |\n"
      "|---|---|---|---|---|---|---|---|\n"
      "| %zu | %llu / %.0f | %llu (%.1f %% of %llu) | %llu (base %llu) | %llu | %llu | %.2f / %.2f ms | %llu (%.2fx) "
      "|\n",
      frames, (unsigned long long)faces, double(flight.face_sum) / double(frames),
      (unsigned long long)viewer.received_total(), 100 * share, (unsigned long long)all_splits,
      (unsigned long long)viewer.down_bytes(), (unsigned long long)base_bytes, (unsigned long long)viewer.up_bytes(),
      (unsigned long long)flight.requests, percentile(flight.latencies, 0.5), percentile(flight.latencies, 0.99),
      (unsigned long long)vi_bytes, double(vi_bytes) / double(std::max<uint64_t>(viewer.down_bytes(), 1)));
  return table;
}

void write_report(const std::string& report, const std::string& model_name, size_t frames, float tolerance,
                  const std::string& table) {
  std::ofstream out(report);
  out << "# pmstream demo: sender-driven streaming of " << model_name << "\n\n"
      << "A client flew " << frames << " frames over the model at tolerance " << tolerance
      << " px, asking the server (in-process, loopback TCP) only when its own hierarchy could not satisfy the view.\n\n"
      << table
      << "\nView-independent: a second client flew the same path in `vi` mode (kim-lee-kobbelt §8's baseline: the "
         "plain PM order, coarse to fine, until each view is satisfied); the factor is its bytes down over the "
         "view-dependent client's.\n\nSnapshots: `snapshots/`.\n";
  if (!out) fail(report, "cannot write the report");
}

}  // namespace

void run_demo_flight(const std::string& pms_path, const std::string& model_name, const FlightOptions& options) {
  const auto catalogue = server::Catalogue::open({pms_path});
  const server::ServedModel& served = *catalogue->find(model_name);
  server::TcpServer tcp(catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  std::printf("server:    %s on 127.0.0.1:%u (TCP, sender-driven)\n", model_name.c_str(), unsigned(tcp.port()));

  const std::vector<Camera> path = demo_flight_path(served.model(), options.frames);
  const std::unique_ptr<client::Viewer> viewer = open_demo_viewer(tcp.port(), model_name, "sender", options.tolerance);
  const uint64_t base_bytes = viewer->down_bytes();
  const std::string snapshots = options.out_dir + "/snapshots";
  if (options.snapshot_every) std::filesystem::create_directories(snapshots);
  const Flight flight = fly(*viewer, path, options, demo_snapshot_look(served.model()), snapshots);

  std::printf("baseline:  the same flight, view-independent (plain PM order) ...");
  std::fflush(stdout);
  const uint64_t vi_bytes = view_independent_bytes(tcp.port(), model_name, path, options.tolerance);
  std::printf(" %llu B down\n", (unsigned long long)vi_bytes);
  tcp.stop();

  const uint64_t all_splits = served.info.vsplits;
  const std::string table = summary_table(*viewer, flight, path.size(), base_bytes, all_splits, vi_bytes);
  std::printf("\n%s\n", table.c_str());
  std::printf("streamed in %.2f s; every vsplit crossed the wire at most once (%llu of the model's %llu were needed)\n",
              flight.seconds, (unsigned long long)viewer->received_total(), (unsigned long long)all_splits);
  const std::string report = options.out_dir + "/report.md";
  write_report(report, model_name, path.size(), options.tolerance, table);
  std::printf("wrote:     %s, %s/\n", report.c_str(), snapshots.c_str());
}

}  // namespace pms::app
