#include "bench/receiver_quality.h"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <optional>

#include "bench/curve_compare.h"
#include "bench/gnuplot.h"
#include "bench/image_quality.h"
#include "bench/quality_curve.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "spm/adapt.h"
#include "spm/stream_order.h"

namespace pms::bench {
using nlohmann::json;
namespace {

// τ = 0 px: every mode streams toward the same image, the full model's visible detail (docs/internals.md,
// "E6 and E8" says why not 1 px); the receiver-driven end is E8's measurement.
constexpr float kTolerance = 0;
// cheng-ooi's curves stop at a PSNR cap: above it the images no longer differ visibly.
constexpr double kPsnrCap = 40;
constexpr double kPsnrSteps[] = {20, 25, 30, 35};

// The area-ranking client's stop rule in E6: a leaf is split while its faces cover a pixel, the area
// analogue of τ = 0.
constexpr uint32_t kStopArea = 1;

struct CurveMode {
  const char* name;
  bool receiver;  // over HTTP; else an in-process session in `mode`
  protocol::StreamMode mode;
  client::Ranking ranking = client::Ranking::error;  // receiver: error over the info form, area over the plain one
};
constexpr CurveMode kModes[] = {
    {"sender-driven", false, protocol::StreamMode::sender_driven},
    {"sender-plain", false, protocol::StreamMode::sender_plain},
    {"receiver-driven", true, protocol::StreamMode::sender_driven},
    {"view-independent", false, protocol::StreamMode::view_independent},
    {"receiver-area plain", true, protocol::StreamMode::sender_driven, client::Ranking::area}};
constexpr size_t kModeCount = std::size(kModes), kReceiver = 2, kViewIndependent = 3;

struct LocalMesh {
  uint64_t faces = 0;
  ImageMetrics metrics;
};

struct ViewRun {
  Viewpoint viewpoint;
  QualityCurve curves[kModeCount];
  std::string errors[kModeCount];  // a client that failed: its curve is empty
  LocalMesh local;                 // local refinement at the same τ, for E8's comparison
  CurveOrder receiver_vs_vi;
};

QualityCurve run_mode(const CurveMode& mode, const BenchModel& m, uint16_t http_port, const Camera& camera,
                      const QualityTarget& target, Renderer& renderer) {
  if (mode.receiver)
    return receiver_curve(http_port, m.name, camera, kTolerance, target, renderer, mode.ranking, kStopArea);
  return session_curve(m, mode.mode, camera, kTolerance, target, renderer);
}

ViewRun run_view(const BenchModel& m, const MeshArrays& full, const Viewpoint& vp, uint16_t http_port,
                 Renderer& renderer) {
  const ModelData& model = m.served->model();
  const QualityTarget target = quality_target(model, full, vp.camera, renderer);
  ViewRun run;
  run.viewpoint = vp;
  for (size_t i = 0; i < kModeCount; ++i) {
    std::fprintf(stderr, "bench: E6 %s %s %s ...\n", m.name.c_str(), vp.label, kModes[i].name);
    try {
      run.curves[i] = run_mode(kModes[i], m, http_port, vp.camera, target, renderer);
    } catch (const std::exception& e) {
      run.errors[i] = e.what();
    }
  }
  const MeshArrays local = refine_for_view(model, vp.camera, kTolerance).mesh;
  Image image;
  renderer.render(as_render(local), target.view, image);
  run.local = {local.indices.size() / 3, compare_images(image, target.reference)};
  run.receiver_vs_vi = compare_curves(run.curves[kReceiver].samples, run.curves[kViewIndependent].samples, kPsnrCap);
  return run;
}

// The curve up to its first sample at the cap, drawn at the cap.
PlotSeries capped_series(const char* title, const std::vector<CurveSample>& samples) {
  PlotSeries series{title, {}, {}};
  for (const CurveSample& s : samples) {
    series.x.push_back(double(s.bytes));
    series.y.push_back(std::min(s.psnr, kPsnrCap));
    if (s.psnr >= kPsnrCap) break;
  }
  return series;
}

std::string plot_view(const BenchContext& context, const std::string& model, const ViewRun& run) {
  Plot plot{"E6 " + model + ", " + run.viewpoint.label + " view: PSNR against bytes received (τ = 0 px, cut at " +
                fixed(kPsnrCap, 0) + " dB)",
            "bytes received (log)",
            "PSNR dB",
            "",
            true,
            false,
            {}};
  for (size_t i = 0; i < kModeCount; ++i) plot.series.push_back(capped_series(kModes[i].name, run.curves[i].samples));
  return plot_markdown(context.options.out_dir, plot, "receiver-e6-" + model + "-" + run.viewpoint.label + ".png",
                       "E6 " + model + " " + run.viewpoint.label);
}

constexpr size_t kE6Columns = 4 + std::size(kPsnrSteps) + 6;

Table e6_table() {
  std::vector<Column> columns = {{"model", false}, {"view", false}, {"mode", false}, {"base B", true}};
  for (double step : kPsnrSteps) columns.push_back({"to " + fixed(step, 0) + " dB", true});
  for (const char* title : {"final B", "payload B", "final PSNR", "faces", "splits", "GETs"})
    columns.push_back({title, true});
  return Table(columns);
}

std::vector<std::string> e6_row(const std::string& model, const ViewRun& run, size_t mode) {
  const QualityCurve& c = run.curves[mode];
  std::vector<std::string> row = {model, run.viewpoint.label, kModes[mode].name};
  if (!run.errors[mode].empty() || c.samples.empty()) {
    row.resize(kE6Columns, "failed");
    return row;
  }
  row.push_back(thousands(c.samples.front().bytes));
  for (double step : kPsnrSteps) {
    const std::optional<uint64_t> bytes = bytes_to_reach(c.samples, step);
    row.push_back(bytes ? thousands(*bytes) : "—");
  }
  const CurveSample& last = c.samples.back();
  row.insert(row.end(), {thousands(last.bytes), thousands(last.payload), psnr_text(last.psnr), thousands(last.faces),
                         thousands(c.splits), kModes[mode].receiver ? thousands(c.requests) : ""});
  return row;
}

Table order_table() {
  return Table({{"model", false},
                {"view", false},
                {"receiver ≥ VI everywhere", false},
                {"byte counts", true},
                {"above", true},
                {"equal", true},
                {"below", true},
                {"first below at B", true},
                {"worst deficit dB", true}});
}

std::vector<std::string> order_row(const std::string& model, const ViewRun& run) {
  const CurveOrder& o = run.receiver_vs_vi;
  return {model,
          run.viewpoint.label,
          o.not_below() ? "yes" : "no",
          thousands(o.compared),
          thousands(o.above),
          thousands(o.equal),
          thousands(o.below),
          o.below ? thousands(o.first_below_bytes) : "",
          o.below ? fixed(o.worst_deficit, 2) : ""};
}

Table e8_table() {
  return Table({{"model", false},
                {"view", false},
                {"full faces", true},
                {"faces", true},
                {"faces %", true},
                {"splits fetched", true},
                {"of", true},
                {"fetched %", true},
                {"PSNR", true},
                {"err px", true},
                {"err %", true},
                {"local τ=0 faces", true},
                {"local PSNR", true}});
}

std::vector<std::string> e8_row(const std::string& model, uint64_t full_faces, uint64_t total_splits,
                                const ViewRun& run, uint64_t pixels) {
  const QualityCurve& c = run.curves[kReceiver];
  if (c.samples.empty())
    return {model, run.viewpoint.label, thousands(full_faces), "failed", "", "", "", "", "", "", "", "", ""};
  const CurveSample& last = c.samples.back();
  return {model,
          run.viewpoint.label,
          thousands(full_faces),
          thousands(last.faces),
          fixed(100.0 * double(last.faces) / double(full_faces), 1),
          thousands(c.splits),
          thousands(total_splits),
          fixed(100.0 * double(c.splits) / double(total_splits), 1),
          psnr_text(last.psnr),
          thousands(last.error_pixels),
          fixed(100.0 * double(last.error_pixels) / double(pixels), 3),
          thousands(run.local.faces),
          psnr_text(run.local.metrics.psnr)};
}

json samples_json(const QualityCurve& c) {
  json samples = json::array();
  for (const CurveSample& s : c.samples)
    samples.push_back({{"bytes", s.bytes},
                       {"payload", s.payload},
                       {"faces", s.faces},
                       {"psnr", psnr_json(s.psnr)},
                       {"error_pixels", s.error_pixels}});
  return samples;
}

json view_json(const ViewRun& run) {
  json modes = json::object();
  for (size_t i = 0; i < kModeCount; ++i) {
    const QualityCurve& c = run.curves[i];
    modes[kModes[i].name] = {{"samples", samples_json(c)}, {"splits", c.splits},   {"requests", c.requests},
                             {"bytes", c.bytes},           {"payload", c.payload}, {"error", run.errors[i]}};
  }
  const CurveOrder& o = run.receiver_vs_vi;
  return {{"view", run.viewpoint.label},
          {"tolerance_px", kTolerance},
          {"psnr_cap", kPsnrCap},
          {"modes", modes},
          {"local",
           {{"faces", run.local.faces},
            {"psnr", psnr_json(run.local.metrics.psnr)},
            {"error_pixels", run.local.metrics.error_pixels}}},
          {"receiver_not_below_vi", o.not_below()},
          {"receiver_vs_vi",
           {{"compared", o.compared},
            {"above", o.above},
            {"equal", o.equal},
            {"below", o.below},
            {"first_below_bytes", o.first_below_bytes},
            {"worst_deficit_db", o.worst_deficit}}}};
}

void print(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

}  // namespace

std::string e6_e8_sections(BenchContext& context, const std::vector<BenchModel>& models, json& records) {
  Table e6 = e6_table(), order = order_table(), e8 = e8_table();
  std::string plots;
  print("\nE6: PSNR against bytes received toward one view, τ = 0 px\n" + e6.header());
  for (size_t k = 0; k < models.size(); ++k) {
    const BenchModel& m = models[k];
    const ModelData& model = m.served->model();
    const MeshArrays full = refine_in_stream_order(model, model.split_order.size());
    Renderer renderer;
    ServeChild server(context.pmstream_exe, {m.pms.string(), "--http-port", "0"});
    const uint16_t http_port = server.listening().at("http_port").get<uint16_t>();
    json views = json::array();
    for (const Viewpoint& vp : quality_viewpoints(model)) {
      const ViewRun run = run_view(m, full, vp, http_port, renderer);
      for (size_t i = 0; i < kModeCount; ++i) {
        print(e6.add_row(e6_row(m.name, run, i)));
        if (!run.errors[i].empty())
          context.failures.push_back("E6 " + m.name + " " + vp.label + " " + kModes[i].name + ": " + run.errors[i]);
      }
      order.add_row(order_row(m.name, run));
      e8.add_row(e8_row(m.name, full.indices.size() / 3, model.split_order.size(), run,
                        uint64_t(vp.camera.width) * vp.camera.height));
      plots += plot_view(context, m.name, run);
      views.push_back(view_json(run));
    }
    server.stop();
    records[k]["e6"] = views;
  }
  print("\nE6 target: on the close view the receiver-driven curve lies above the view-independent one\n" +
        order.markdown());
  print("\nE8: the receiver-driven client fetching only visible splits (τ = 0 px), against the full model\n" +
        e8.markdown());
  std::string section =
      "### E6: PSNR against bytes received, four modes and the area-ranking client toward one view\n\n" +
      e6.markdown() +
      "\nEach row: a fresh client from the base mesh streaming toward one view at τ = 0 px (one frame at that camera), "
      "its mesh rendered with the project's renderer against the full model's image there at geometrically spaced "
      "byte counts (every ×" +
      fixed(kCurveSampleGrowth, 2) +
      "). Bytes are what the client received as counted on "
      "the wire: whole frames of the TCP protocol for sender-driven, sender-plain (kim-lee-kobbelt §6.3) and "
      "view-independent (an in-process session); for receiver-driven, HTTP responses with their status lines and "
      "headers (GET /models, the base, the code tables, the split GETs) from a `serve --http-port` child on "
      "loopback; payload B = the same without framing. \"to N dB\" = bytes at the first sample at or above N dB; "
      "— = never. Views: far and close are the zoom path's ends, mid the sender group's E5 close view (the refine "
      "group's quality table uses the same three). Same .pms and 16-bit grid for every mode. receiver-area plain: "
      "the receiver-driven client ranking by visible area alone over the plain records (cheng-ooi's client; "
      "docs/protocol.md, \"The plain form\"), splitting while a leaf's faces cover at least 1 pixel.\n\n";
  section +=
      "### E6 target: receiver-driven against view-independent\n\n" + order.markdown() +
      "\nAt every byte count where either curve has a sample and both clients hold a mesh, the PSNR each shows then "
      "(its last sample's, capped at " +
      fixed(kPsnrCap, 0) +
      " dB); issue 19's target is the close view's row. Both "
      "show the base mesh until their first splits arrive, so \"equal\" counts the start too.\n\n";
  section += plots;
  section +=
      "### E8: only visible splits fetched (cheng-ooi Table 2)\n\n" + e8.markdown() +
      "\nThe receiver-driven client of E6 at its end (τ = 0 px: qrefine with frustum and back-face culling only), "
      "its mesh against the full model's image; splits fetched = the splits it received, of the model's total. "
      "Local τ = 0: refinement of the whole model in this process for the same view (the refine group's τ = 0 "
      "column).\n\n";
  return section;
}

}  // namespace pms::bench
