// The "refine" group (issue: truly selective refinement engine): on dragon, the adaptation loop along a
// 180-frame scan path at τ = 1 px (per-frame time, operations per second, faces), the engine's raw
// vsplit/ecol throughput, the renderer's triangles per second, and the quality table at three
// viewpoints: the refined mesh's image against the full mesh's at τ = 0 px (culling only, cheng-ooi
// 2008 Table 2) and τ = 1 px, beside the view-independent mesh with as many faces (the first K splits
// in stream order, kim-lee-kobbelt Fig 10).
#include <algorithm>
#include <cstdio>

#include "apps/camera_path.h"
#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "bench/bench.h"
#include "bench/bench_refine.h"
#include "bench/child_process.h"
#include "bench/image_quality.h"
#include "bench/report.h"
#include "common/error.h"
#include "render/render.h"
#include "spm/adapt.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/stream_order.h"
#include "spm/vertex_hierarchy.h"

namespace pms::bench {
using app::make_camera_path;
using app::PathKind;
using app::PathOptions;
using app::percentile;
using app::Stopwatch;
namespace fs = std::filesystem;
using nlohmann::json;

void print_now(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

namespace {

constexpr uint32_t kScanFrames = 180, kQuickScanFrames = 40;
constexpr uint32_t kRenderRepeats = 5;

struct PathRun {
  std::vector<double> frame_ms;
  uint64_t ops = 0;
  double adapt_seconds = 0;
  std::vector<double> faces;
};

PathRun run_path(const ModelData& model, const std::vector<Camera>& path, float tolerance) {
  VertexHierarchy h = complete_hierarchy(model);
  SelectiveMesh mesh(h, model.base_faces);
  SelectiveRefinement refinement(mesh, model.scale, AdaptOptions{tolerance, 0, 0});
  // The first view from the base mesh is a load, not a frame: converge on it untimed.
  refinement.set_view(make_view(path[0], model.bbox_min, model.bbox_max));
  refinement.converge();
  PathRun run;
  for (const Camera& camera : path) {
    Stopwatch clock;
    refinement.set_view(make_view(camera, model.bbox_min, model.bbox_max));
    const FrameStats stats = refinement.adapt();
    const double seconds = clock.seconds();
    run.frame_ms.push_back(1000 * seconds);
    run.adapt_seconds += seconds;
    run.ops += stats.ops();
    run.faces.push_back(double(mesh.face_count()));
  }
  return run;
}

// Raw engine throughput: every split in PM order, then every collapse in reverse.
double engine_ops_per_second(const ModelData& model, uint64_t& ops) {
  VertexHierarchy h = complete_hierarchy(model);
  SelectiveMesh mesh(h, model.base_faces);
  std::vector<uint32_t> slots;
  slots.reserve(model.split_order.size());
  for (uint32_t node : model.split_order) slots.push_back(h.find(model.id(node)));
  // As a client applying a received batch would: it knows the next operations, so it prefetches them.
  constexpr int kStages = SelectiveMesh::kPrefetchStages;
  const auto& ahead = SelectiveMesh::kPrefetchAhead;
  const size_t n = slots.size();
  Stopwatch clock;
  for (size_t i = 0; i < n; ++i) {
    for (int stage = 0; stage < kStages; ++stage)
      if (i + ahead[stage] < n) mesh.prefetch_vsplit(slots[i + ahead[stage]], stage);
    mesh.vsplit(slots[i]);
  }
  for (size_t i = n; i-- > 0;) {
    for (int stage = 0; stage < kStages; ++stage)
      if (i >= ahead[stage]) mesh.prefetch_ecol(slots[i - ahead[stage]], stage);
    mesh.ecol(slots[i]);
  }
  const double seconds = clock.seconds();
  ops = 2 * slots.size();
  if (mesh.face_count() != model.base_faces.size() / 3)
    fail("bench refine", "collapsing everything did not give the base");
  return double(ops) / seconds;
}

struct Quality {
  uint64_t faces = 0;
  ImageMetrics metrics;
};

// The reference dimmed, every pixel the image gets wrong in red: where the error is (issue 3's diagnosis
// of the τ = 0 failures started from these).
void save_diff_png(const fs::path& path, const Image& image, const Image& reference) {
  Image diff = reference;
  for (size_t p = 0; p < diff.rgb.size(); p += 3) {
    const bool differs = !std::equal(&image.rgb[p], &image.rgb[p] + 3, &reference.rgb[p]);
    const uint8_t marked[3] = {255, 0, 0};
    for (int k = 0; k < 3; ++k) diff.rgb[p + k] = differs ? marked[k] : uint8_t(reference.rgb[p + k] / 3);
  }
  save_png(path.string(), diff);
}

// Renders `mesh`, compares it with the reference and writes the diff image to `diff_png`.
Quality quality_of(const MeshArrays& mesh, const ViewParams& view, const Image& reference, Renderer& renderer,
                   const fs::path& diff_png) {
  Image image;
  renderer.render(as_render(mesh), view, image);
  save_diff_png(diff_png, image, reference);
  return {mesh.indices.size() / 3, compare_images(image, reference)};
}

// The view-independent mesh with (about) `faces` faces: each split adds two faces, one on the boundary.
MeshArrays view_independent(const ModelData& model, uint64_t faces) {
  const uint64_t base = model.base_faces.size() / 3;
  uint64_t k = faces > base ? (faces - base) / 2 : 0;
  MeshArrays mesh = refine_in_stream_order(model, k);
  while (mesh.indices.size() / 3 < faces && k < model.split_order.size()) {
    k += std::max<uint64_t>(1, (faces - mesh.indices.size() / 3) / 2);
    mesh = refine_in_stream_order(model, k);
  }
  return mesh;
}

std::string face_share(uint64_t faces, double full_faces) { return fixed(100 * double(faces) / full_faces, 1); }

// In a child process, as a user runs `pmstream build`; `deviation` as its --deviation takes it.
std::unique_ptr<PmsFile> build_pms(const BenchContext& context, const std::string& name, const std::string& deviation) {
  const fs::path pms = context.temp_dir / (name + "-" + deviation + ".pms");
  std::fprintf(stderr, "bench: building %s (deviation %s) ... ", name.c_str(), deviation.c_str());
  const ChildResult built = run_child({context.pmstream_exe, "build", find_model(context.models_dir, name).string(),
                                       "-o", pms.string(), "--deviation", deviation});
  if (!built.ok()) fail(name, "pmstream build: " + built.failure());
  std::fprintf(stderr, "%.2f s\n", built.wall_seconds);
  return PmsFile::open(pms.string());
}

// The adaptation loop along the scan path at τ = 1 px, beside the engine's raw rate.
std::string adaptation_section(const ModelData& model, const std::string& name, bool quick, json& out) {
  PathOptions scan_options;
  scan_options.frames = quick ? kQuickScanFrames : kScanFrames;
  const std::vector<Camera> scan = make_camera_path(PathKind::scan, model, scan_options);
  std::fprintf(stderr, "bench: %u-frame scan at 1 px ...\n", scan_options.frames);
  const PathRun run = run_path(model, scan, 1.0f);
  uint64_t engine_ops = 0;
  const double engine_rate = engine_ops_per_second(model, engine_ops);
  Table adapt({{"model", false},
               {"frames", true},
               {"median ms", true},
               {"p99 ms", true},
               {"loop ops/s", true},
               {"engine ops/s", true},
               {"faces (median)", true}});
  adapt.add_row({name, std::to_string(scan.size()), fixed(percentile(run.frame_ms, 0.5), 3),
                 fixed(percentile(run.frame_ms, 0.99), 3),
                 thousands(uint64_t(double(run.ops) / std::max(run.adapt_seconds, 1e-9))),
                 thousands(uint64_t(engine_rate)), thousands(uint64_t(percentile(run.faces, 0.5)))});
  out["adapt"] = {{"frames", scan.size()},    {"frame_ms", run.frame_ms},
                  {"ops", run.ops},           {"adapt_seconds", run.adapt_seconds},
                  {"engine_ops", engine_ops}, {"engine_ops_per_second", engine_rate},
                  {"faces", run.faces}};
  print_now("\nAdaptation along a scan path at τ = 1 px (targets: median ≤ 4 ms, ≥ 3 M ops/s)\n" + adapt.markdown());
  return "### Adaptation along a " + std::to_string(scan.size()) + "-frame scan path, τ = 1 px (" + name + ")\n\n" +
         adapt.markdown() + "\nEngine ops/s: every vsplit in PM order, then every ecol in reverse, one core.\n\n";
}

std::string renderer_section(const ModelData& model, const MeshArrays& full, const Camera& camera, Renderer& renderer,
                             json& out) {
  Image image;
  Stopwatch render_clock;
  for (uint32_t i = 0; i < kRenderRepeats; ++i)
    renderer.render(as_render(full), make_view(camera, model.bbox_min, model.bbox_max), image);
  const double triangles_per_second = double(kRenderRepeats) * double(full.indices.size() / 3) / render_clock.seconds();
  out["render_triangles_per_second"] = triangles_per_second;
  print_now("\nRenderer: " + thousands(uint64_t(triangles_per_second)) + " triangles/s (" +
            thousands(full.indices.size() / 3) + " faces, " + std::to_string(camera.width) + "x" +
            std::to_string(camera.height) + ")\n");
  return "Renderer: " + thousands(uint64_t(triangles_per_second)) + " triangles/s on the full mesh.\n\n";
}

// One viewpoint's meshes, each against the full mesh's image there.
struct ViewQuality {
  Quality tau0, tau1, vi;        // the default model (Hoppe's estimate)
  Quality bound_tau1, bound_vi;  // the model built with --deviation bound
};

ViewQuality view_quality(const ModelData& model, const ModelData& bounded, const MeshArrays& full, const Viewpoint& vp,
                         Renderer& renderer, const fs::path& out_dir) {
  const ViewParams view = make_view(vp.camera, model.bbox_min, model.bbox_max);
  Image reference;
  renderer.render(as_render(full), view, reference);
  const auto against_full = [&](const MeshArrays& mesh, const char* what) {
    return quality_of(mesh, view, reference, renderer,
                      out_dir / (std::string("refine-") + vp.label + "-" + what + "-diff.png"));
  };
  ViewQuality q;
  q.tau0 = against_full(refine_for_view(model, vp.camera, 0.0f).mesh, "tau0");
  q.tau1 = against_full(refine_for_view(model, vp.camera, 1.0f).mesh, "tau1");
  q.vi = against_full(view_independent(model, q.tau1.faces), "vi");
  q.bound_tau1 = against_full(refine_for_view(bounded, vp.camera, 1.0f).mesh, "bound-tau1");
  q.bound_vi = against_full(view_independent(bounded, q.bound_tau1.faces), "bound-vi");
  return q;
}

Table quality_table() {
  return Table({{"view", false},
                {"full faces", true},
                {"τ=0 faces", true},
                {"τ=0 %", true},
                {"τ=0 PSNR", true},
                {"τ=0 err px", true},
                {"τ=0 err %", true},
                {"τ=1 faces", true},
                {"τ=1 %", true},
                {"τ=1 PSNR", true},
                {"τ=1 err px", true},
                {"VI PSNR", true},
                {"VI err px", true}});
}

std::vector<std::string> quality_row(const char* label, double full_faces, const ViewQuality& q) {
  return {label,
          thousands(uint64_t(full_faces)),
          thousands(q.tau0.faces),
          face_share(q.tau0.faces, full_faces),
          psnr_text(q.tau0.metrics.psnr),
          thousands(q.tau0.metrics.error_pixels),
          fixed(100 * q.tau0.metrics.error_fraction, 3),
          thousands(q.tau1.faces),
          face_share(q.tau1.faces, full_faces),
          psnr_text(q.tau1.metrics.psnr),
          thousands(q.tau1.metrics.error_pixels),
          psnr_text(q.vi.metrics.psnr),
          thousands(q.vi.metrics.error_pixels)};
}

Table bound_table() {
  return Table({{"view", false},
                {"τ=1 faces", true},
                {"τ=1 %", true},
                {"τ=1 PSNR", true},
                {"τ=1 err px", true},
                {"VI PSNR", true},
                {"VI err px", true}});
}

std::vector<std::string> bound_row(const char* label, double full_faces, const ViewQuality& q) {
  return {label,
          thousands(q.bound_tau1.faces),
          face_share(q.bound_tau1.faces, full_faces),
          psnr_text(q.bound_tau1.metrics.psnr),
          thousands(q.bound_tau1.metrics.error_pixels),
          psnr_text(q.bound_vi.metrics.psnr),
          thousands(q.bound_vi.metrics.error_pixels)};
}

json quality_json(const Quality& q) {
  return {{"faces", q.faces}, {"psnr", psnr_json(q.metrics.psnr)}, {"error_pixels", q.metrics.error_pixels}};
}

json view_quality_json(const char* label, double full_faces, const ViewQuality& q) {
  return {{"view", label},
          {"full_faces", full_faces},
          {"tau0", quality_json(q.tau0)},
          {"tau1", quality_json(q.tau1)},
          {"vi", quality_json(q.vi)},
          {"bound_tau1", quality_json(q.bound_tau1)},
          {"bound_vi", quality_json(q.bound_vi)}};
}

// The quality table at three viewpoints, then the same views on the model built with the deviation bound
// (build --deviation bound): more faces for τ = 1 px, and how that compares with the view-independent mesh
// of that size.
std::string quality_sections(const BenchContext& context, const std::string& name, const ModelData& model,
                             const MeshArrays& full, const std::vector<Viewpoint>& views, Renderer& renderer,
                             json& out) {
  Table quality = quality_table();
  json per_view = json::array();
  const auto bounded_file = build_pms(context, name, "bound");
  const ModelData& bounded = bounded_file->model();
  Table bound = bound_table();
  const double full_faces = double(full.indices.size() / 3);
  for (const Viewpoint& vp : views) {
    const ViewQuality q = view_quality(model, bounded, full, vp, renderer, context.options.out_dir);
    quality.add_row(quality_row(vp.label, full_faces, q));
    bound.add_row(bound_row(vp.label, full_faces, q));
    per_view.push_back(view_quality_json(vp.label, full_faces, q));
  }
  out["quality"] = per_view;
  print_now(
      "\nImage quality against the full mesh (targets: τ=0 err ≤ 0.2 %, PSNR ≥ 35 dB, ≤ 60 % faces close; τ=1 ≤ 30 % "
      "faces "
      "close, better than VI at mid and close)\n" +
      quality.markdown());
  print_now(
      "\nThe same views, model built with --deviation bound (a bound on the surface below each node instead of Hoppe's "
      "estimate)\n" +
      bound.markdown());
  return "### Image quality against the full mesh\n\n" + quality.markdown() +
         "\nVI = the first K splits in stream order with at least the τ = 1 px mesh's face count. "
         "refine-VIEW-{tau0,tau1,vi}-diff.png mark the pixels that differ in red.\n\n" +
         "### The same views, model built with `--deviation bound`\n\n" + bound.markdown() +
         "\nA bound on the input surface below each node instead of the default, Hoppe's estimate: more faces for "
         "τ = 1 px (and more bytes to stream them, sender E5), against the view-independent mesh of that size.\n\n";
}

}  // namespace

void run_refine_group(BenchContext& context) {
  std::string section = "## refine: selective refinement, renderer and image quality\n\n";
  if (skipped_without_models(context, section)) return;
  const bool quick = context.options.quick;
  const std::string name = context.options.models.empty() ? (quick ? "bunny" : "dragon") : context.options.models[0];
  const auto file = build_pms(context, name, "estimate");  // the default
  const ModelData& model = file->model();
  json out = {{"command", context.options.command_line}, {"machine", machine_json()}, {"model", name}};
  section += adaptation_section(model, name, quick, out);
  section += srmesh_comparison_section(context, out);

  const MeshArrays full = refine_in_stream_order(model, model.split_order.size());
  Renderer renderer;
  PathOptions orbit_options;
  orbit_options.frames = 3;
  const std::vector<Camera> orbit = make_camera_path(PathKind::orbit, model, orbit_options);
  section += renderer_section(model, full, orbit[0], renderer, out);
  section += quality_sections(context, name, model, full, quality_viewpoints(model), renderer, out);
  write_text_file(context.options.out_dir / "refine.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
