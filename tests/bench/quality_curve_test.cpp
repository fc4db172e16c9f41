// E6's curves (bench/quality_curve.h, curve_compare.h): how curves are read against each other, and on
// the bunny, every mode's real client streaming toward one view: bytes grow at every sample, the last sample is
// the client's own final mesh and byte counts, sampling does not change what the client fetches, and the
// receiver-driven end (E8) is local refinement's mesh.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/bench_model.h"
#include "bench/curve_compare.h"
#include "bench/image_quality.h"
#include "bench/quality_curve.h"
#include "bench/serve_child.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "spm/adapt.h"
#include "spm/stream_order.h"
#include "test_support.h"

namespace pms::bench {
namespace {

std::vector<CurveSample> curve(std::initializer_list<std::pair<uint64_t, double>> points) {
  std::vector<CurveSample> samples;
  for (const auto& [bytes, psnr] : points) samples.push_back({bytes, bytes, 0, psnr, 0});
  return samples;
}

TEST(CurveCompare, StepsBetweenSamplesAndCap) {
  const std::vector<CurveSample> a = curve({{100, 10}, {200, 20}, {400, 45}});
  EXPECT_EQ(bytes_to_reach(a, 20), 200u);
  EXPECT_EQ(bytes_to_reach(a, 50), std::nullopt);
  EXPECT_EQ(psnr_at(a, 99, 40), std::nullopt);
  EXPECT_EQ(psnr_at(a, 399, 40), 20);
  EXPECT_EQ(psnr_at(a, 1000, 40), 40);  // the final mesh is kept, capped
}

TEST(CurveCompare, BelowIsFoundWhereverItIs) {
  const std::vector<CurveSample> upper = curve({{100, 10}, {150, 30}, {300, 50}});
  const std::vector<CurveSample> lower = curve({{90, 10}, {200, 35}, {250, 42}});
  const CurveOrder order = compare_curves(upper, lower, 40);
  // 90 is before upper's first sample; at 100 both show 10; 150: 30 > 10; 200: 30 < 35; 250: 30 < 40; 300: 40 = 40.
  EXPECT_EQ(order.compared, 5u);
  EXPECT_EQ(order.equal, 2u);
  EXPECT_EQ(order.above, 1u);
  EXPECT_EQ(order.below, 2u);
  EXPECT_EQ(order.first_below_bytes, 200u);
  EXPECT_DOUBLE_EQ(order.worst_deficit, 10);
  EXPECT_FALSE(order.not_below());
  EXPECT_TRUE(compare_curves(lower, curve({{90, 10}}), 40).not_below());
}

double psnr_of(client::ClientSession& session, const QualityTarget& target, Renderer& renderer) {
  MeshArrays arrays;
  session.mesh().extract(arrays);
  Image image;
  renderer.render(as_render(arrays), target.view, image);
  return compare_images(image, target.reference).psnr;
}

void expect_well_formed(const QualityCurve& c, bool never_coarsens, const char* mode) {
  SCOPED_TRACE(mode);
  ASSERT_GE(c.samples.size(), 5u);
  for (size_t i = 1; i < c.samples.size(); ++i) {
    EXPECT_GT(c.samples[i].bytes, c.samples[i - 1].bytes);
    EXPECT_GE(c.samples[i].payload, c.samples[i - 1].payload);
    EXPECT_LT(c.samples[i].payload, c.samples[i].bytes);
    if (never_coarsens) {
      EXPECT_GE(c.samples[i].faces, c.samples[i - 1].faces);
    }
  }
  EXPECT_EQ(c.samples.back().bytes, c.bytes);
  EXPECT_EQ(c.samples.back().payload, c.payload);
  EXPECT_GT(c.samples.back().psnr, c.samples.front().psnr);
}

struct Bunny {
  BenchContext context;
  BenchModel m;
  MeshArrays full;
  Camera camera;
};

Bunny bunny() {
  Bunny b;
  b.context.models_dir = test::shared_models_dir();
  b.context.temp_dir = test::temp_dir();
  b.context.pmstream_exe = PMSTREAM_BINARY;
  b.m = prepare_model(b.context, "bunny");
  const ModelData& model = b.m.served->model();
  b.full = refine_in_stream_order(model, model.split_order.size());
  b.camera = quality_viewpoints(model)[1].camera;  // mid
  return b;
}

TEST(QualityCurve, InProcessModesOnBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const Bunny b = bunny();
  Renderer renderer;
  const QualityTarget target = quality_target(b.m.served->model(), b.full, b.camera, renderer);
  for (const protocol::StreamMode mode : {protocol::StreamMode::sender_driven, protocol::StreamMode::sender_plain,
                                          protocol::StreamMode::view_independent}) {
    const QualityCurve c = session_curve(b.m, mode, b.camera, 0, target, renderer);
    const bool applies_as_they_come = mode != protocol::StreamMode::sender_driven;
    expect_well_formed(c, applies_as_they_come, protocol::mode_name(mode));
    // The same client without the probe: the same bytes, splits and final mesh.
    client::ClientOptions options{0};
    options.mode = mode;
    client::StreamingClient plain(in_process_session(b.m).transport, options);
    plain.open(b.m.name);
    plain.frame(b.camera);
    EXPECT_EQ(plain.counters().bytes_down, c.bytes) << protocol::mode_name(mode);
    EXPECT_EQ(plain.session().splits_received(), c.splits) << protocol::mode_name(mode);
    EXPECT_EQ(plain.session().mesh().face_count(), c.samples.back().faces) << protocol::mode_name(mode);
    EXPECT_EQ(psnr_of(plain.session(), target, renderer), c.samples.back().psnr) << protocol::mode_name(mode);
  }
}

TEST(QualityCurve, ReceiverDrivenOnBunnyEndsAtLocalRefinement) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const Bunny b = bunny();
  const ModelData& model = b.m.served->model();
  Renderer renderer;
  const QualityTarget target = quality_target(model, b.full, b.camera, renderer);
  ServeChild server(PMSTREAM_BINARY, {b.m.pms.string(), "--http-port", "0"});
  const uint16_t port = server.listening().at("http_port").get<uint16_t>();
  const QualityCurve c = receiver_curve(port, b.m.name, b.camera, 0, target, renderer);
  expect_well_formed(c, false, "receiver");
  EXPECT_GT(c.requests, 0u);

  client::ReceiverOptions options;
  options.tolerance = 0;
  client::ReceiverClient plain(client::HttpUrl{"127.0.0.1", port, ""}, options);
  plain.open(b.m.name);
  plain.frame(b.camera);
  EXPECT_EQ(plain.counters().bytes_down, c.bytes);
  EXPECT_EQ(plain.counters().payload_down, c.payload);
  EXPECT_EQ(plain.split_requests(), c.requests);
  EXPECT_EQ(plain.session().splits_received(), c.splits);
  EXPECT_EQ(psnr_of(plain.session(), target, renderer), c.samples.back().psnr);

  // E8: the mesh local refinement makes for the same view and τ (its positions are the model's own, not the
  // wire's 16-bit grid, so only the faces are compared), from its splits and the few more that descendant
  // depth brings (the receiver client's descendant_depth(): under 1 %).
  const MeshArrays local = refine_for_view(model, b.camera, 0).mesh;
  EXPECT_EQ(c.samples.back().faces, local.indices.size() / 3);
  const size_t needed = local.positions.size() / 3 - model.root_count;
  EXPECT_GE(c.splits, needed);
  EXPECT_LE(c.splits, needed + needed / 100);
  EXPECT_LT(c.splits, model.split_order.size());
  server.stop();
}

}  // namespace
}  // namespace pms::bench
