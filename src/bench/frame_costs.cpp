// E13, kim-lee-kobbelt 2005 Fig. 8: "the times required for the view-dependent refinement and the rendering
// are dominated by the number of faces". A sender-driven client streams the model along two laps of the look
// path (Fig. 5) in process; per frame its mesh's faces, the client's CPU time for the frame (adaptation and
// attaching the splits that arrived: the frame's thread time less the server's), the server's, and the
// software renderer's time to draw the client's mesh on one thread.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "apps/camera_path.h"
#include "apps/percentile.h"
#include "bench/gnuplot.h"
#include "bench/image_quality.h"
#include "bench/report.h"
#include "bench/sender_figures.h"
#include "client/streaming_client.h"
#include "render/render.h"

namespace pms::bench {
using app::PathKind;
using app::percentile;
using nlohmann::json;
namespace {

constexpr uint32_t kLapFrames = 120, kQuickLapFrames = 30;
constexpr float kTolerance = 1;

struct FrameCosts {
  std::vector<double> faces, client_ms, server_ms, render_ms, down_bytes;
};

FrameCosts fly(const BenchModel& m, const std::vector<Camera>& lap) {
  InProcessSession in_process = in_process_session(m);
  const std::shared_ptr<double> server_seconds = in_process.server_seconds;
  client::StreamingClient client(std::move(in_process.transport), client::ClientOptions{kTolerance});
  client.open(m.name);
  const ModelData& model = m.served->model();
  Renderer renderer;
  RenderOptions one_thread;
  one_thread.threads = 1;  // the renderer's own cost, not the share of the machine's cores it got
  Image image;
  MeshArrays mesh;
  FrameCosts costs;
  for (int pass = 0; pass < 2; ++pass)
    for (const Camera& camera : lap) {
      const double server_before = *server_seconds, start = thread_seconds();
      const client::FrameReport r = client.frame(camera);
      const double server = *server_seconds - server_before;
      costs.client_ms.push_back(1000 * (thread_seconds() - start - server));
      costs.server_ms.push_back(1000 * server);
      client.session().mesh().extract(mesh);
      const double render_start = thread_seconds();
      renderer.render(as_render(mesh), make_view(camera, model.bbox_min, model.bbox_max), image, one_thread);
      costs.render_ms.push_back(1000 * (thread_seconds() - render_start));
      costs.faces.push_back(double(r.faces));
      costs.down_bytes.push_back(double(r.down_bytes));
    }
  return costs;
}

// Pearson's r: how far a time follows the faces (the figure's claim), whatever the machine's speed.
double correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = std::min(x.size(), y.size());
  if (n < 2) return 0;
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= double(n), my /= double(n);
  double sxy = 0, sxx = 0, syy = 0;
  for (size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0;
}

std::vector<double> slice(const std::vector<double>& v, size_t begin, size_t end) {
  return {v.begin() + ptrdiff_t(begin), v.begin() + ptrdiff_t(std::min(end, v.size()))};
}

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

Table costs_table() {
  return Table({{"lap", true},
                {"frames", true},
                {"faces median", true},
                {"faces max", true},
                {"client ms median", true},
                {"client ms p99", true},
                {"server ms median", true},
                {"render ms median", true},
                {"render ms p99", true},
                {"render ms / 100k faces", true},
                {"r(faces, client ms)", true},
                {"r(faces, render ms)", true}});
}

void add_lap_row(Table& table, const FrameCosts& c, size_t lap, size_t frames) {
  const size_t b = lap * frames, e = b + frames;
  const std::vector<double> faces = slice(c.faces, b, e), client = slice(c.client_ms, b, e),
                            server = slice(c.server_ms, b, e), render = slice(c.render_ms, b, e);
  table.add_row({std::to_string(lap + 1), std::to_string(frames), thousands(uint64_t(percentile(faces, 0.5))),
                 thousands(uint64_t(*std::max_element(faces.begin(), faces.end()))), fixed(percentile(client, 0.5), 2),
                 fixed(percentile(client, 0.99), 2), fixed(percentile(server, 0.5), 2),
                 fixed(percentile(render, 0.5), 2), fixed(percentile(render, 0.99), 2),
                 fixed(1e5 * sum(render) / std::max(sum(faces), 1.0), 2), fixed(correlation(faces, client), 2),
                 fixed(correlation(faces, render), 2)});
}

std::string plot(const BenchContext& context, const BenchModel& m, const FrameCosts& c) {
  std::vector<double> frames;
  for (size_t i = 0; i < c.faces.size(); ++i) frames.push_back(double(i));
  Plot p{"E13 (Fig. 8): " + m.name + " streamed along two laps of the look path, tau = 1 px",
         "frame",
         "ms (thread CPU)",
         "faces",
         false,
         false,
         {{"client: adapt + attach", frames, c.client_ms},
          {"render (software, 1 thread)", frames, c.render_ms},
          {"server", frames, c.server_ms},
          {"faces", frames, c.faces, true}}};
  return plot_markdown(context.options.out_dir, p, "sender-e13-" + m.name + ".png", "faces and times per frame");
}

}  // namespace

std::string frame_costs_section(const BenchContext& context, const BenchModel& m, bool quick, json& out) {
  const uint32_t frames = quick ? kQuickLapFrames : kLapFrames;
  std::fprintf(stderr, "bench: E13 two laps of the look path on %s ...\n", m.name.c_str());
  const FrameCosts c = fly(m, path_of(m, PathKind::look, frames));
  Table table = costs_table();
  for (size_t lap = 0; lap < 2; ++lap) add_lap_row(table, c, lap, frames);
  out["e13"] = {{"model", m.name},           {"tolerance_px", kTolerance},   {"lap_frames", frames},
                {"faces", c.faces},          {"client_ms", c.client_ms},     {"server_ms", c.server_ms},
                {"render_ms", c.render_ms},  {"down_bytes", c.down_bytes}};
  std::fputs(("\nE13: faces and times per frame along the look path on " + m.name + " (Fig 8)\n" + table.markdown())
                 .c_str(),
             stdout);
  return "### E13: faces, refinement and rendering time per frame (Fig. 8, " + m.name + ")\n\n" + table.markdown() +
         "\n" + plot(context, m, c) +
         "\nThe paper streams Buddha (not among our models; this is the largest we have) and plots faces, "
         "refinement and rendering time per frame; its peaks come where the viewpoint jumps. Here a sender-driven "
         "client (τ = 1 px) streams two laps of the look path in process: \"client\" is the frame's thread CPU time "
         "less the server's (adaptation and attaching the splits that arrived), \"render\" the software renderer "
         "drawing the client's mesh on one thread (800 × 600), both CPU time so the machine's other load counts "
         "less. Lap 2 streams nothing (E4), so its client time is adaptation alone. r = Pearson's correlation "
         "with the faces over the lap: the figure's claim, which holds whatever the machine's speed; the times "
         "themselves were taken on a shared, loaded machine and need a rerun on a quiet one.\n\n";
}

}  // namespace pms::bench
