#include "bench/quality_curve.h"

#include "bench/image_quality.h"
#include "bench/probed_transport.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "common/error.h"

namespace pms::bench {
namespace {

// Collects a curve's samples from a client's session as the bytes it has received grow.
class CurveSampler {
 public:
  CurveSampler(const QualityTarget& target, Renderer& renderer, bool refines_itself)
      : target_(target), renderer_(renderer), refines_itself_(refines_itself) {}

  // While the client streams toward the view: a sample once the bytes have grown enough since the last one.
  void during_view(client::ClientSession& session, uint64_t bytes, uint64_t payload) {
    if (streaming_ && bytes >= next_bytes_) take(session, bytes, payload);
  }
  // The base mesh, before the view.
  void base(client::ClientSession& session, uint64_t bytes, uint64_t payload) {
    take(session, bytes, payload);
    streaming_ = true;
  }
  // The client's final mesh for the view; it replaces a sample at the same byte count.
  std::vector<CurveSample> finish(client::ClientSession& session, uint64_t bytes, uint64_t payload) {
    streaming_ = false;
    if (!samples_.empty() && samples_.back().bytes == bytes) samples_.pop_back();
    take(session, bytes, payload);
    return std::move(samples_);
  }

 private:
  void take(client::ClientSession& session, uint64_t bytes, uint64_t payload) {
    // The mode's own frame adapts once its answer is in: here it shows what the splits held so far give.
    if (refines_itself_ && streaming_) session.refinement().adapt();
    session.mesh().extract(arrays_);
    renderer_.render(as_render(arrays_), target_.view, image_);
    const ImageMetrics metrics = compare_images(image_, target_.reference);
    samples_.push_back({bytes, payload, arrays_.indices.size() / 3, metrics.psnr, metrics.error_pixels});
    next_bytes_ = uint64_t(double(bytes) * kCurveSampleGrowth) + 1;
  }

  const QualityTarget& target_;
  Renderer& renderer_;
  const bool refines_itself_;
  bool streaming_ = false;
  uint64_t next_bytes_ = 0;
  std::vector<CurveSample> samples_;
  MeshArrays arrays_;
  Image image_;
};

}  // namespace

QualityTarget quality_target(const ModelData& model, const MeshArrays& full, const Camera& camera, Renderer& renderer) {
  QualityTarget target;
  target.view = make_view(camera, model.bbox_min, model.bbox_max);
  renderer.render(as_render(full), target.view, target.reference);
  return target;
}

QualityCurve session_curve(const BenchModel& m, protocol::StreamMode mode, const Camera& camera, float tolerance_px,
                           const QualityTarget& target, Renderer& renderer) {
  // The sender-driven client refines on its own from the packets' refinement info; the other two apply
  // each split as it comes.
  CurveSampler sampler(target, renderer, mode == protocol::StreamMode::sender_driven);
  client::StreamingClient* self = nullptr;
  auto transport =
      std::make_unique<ProbedTransport>(in_process_session(m).transport, [&](const client::LinkCounters& c) {
        if (self != nullptr) sampler.during_view(self->session(), c.bytes_down, c.payload_down());
      });
  client::ClientOptions options{tolerance_px};
  options.mode = mode;
  client::StreamingClient client(std::move(transport), options);
  client.open(m.name);
  sampler.base(client.session(), client.counters().bytes_down, client.counters().payload_down());
  self = &client;
  client.frame(camera);
  self = nullptr;
  QualityCurve curve;
  curve.bytes = client.counters().bytes_down;
  curve.payload = client.counters().payload_down();
  curve.splits = client.session().splits_received();
  curve.samples = sampler.finish(client.session(), curve.bytes, curve.payload);
  return curve;
}

QualityCurve receiver_curve(uint16_t http_port, const std::string& model, const Camera& camera, float tolerance_px,
                            const QualityTarget& target, Renderer& renderer, client::Ranking ranking,
                            uint32_t stop_area) {
  // Either ranking refines itself: the info form by qrefine, the plain form making every split it holds.
  CurveSampler sampler(target, renderer, true);
  client::ReceiverClient* self = nullptr;
  client::ReceiverOptions options;
  options.tolerance = tolerance_px;
  options.ranking = ranking;
  options.stop_area = stop_area;
  options.on_attached = [&] {
    if (self != nullptr)
      sampler.during_view(self->session(), self->counters().bytes_down, self->counters().payload_down);
  };
  client::ReceiverClient client(client::HttpUrl{"127.0.0.1", http_port, ""}, options);
  client.open(model);
  sampler.base(client.session(), client.counters().bytes_down, client.counters().payload_down);
  self = &client;
  client.frame(camera);
  self = nullptr;
  QualityCurve curve;
  curve.bytes = client.counters().bytes_down;
  curve.payload = client.counters().payload_down;
  curve.splits = client.session().splits_received();
  curve.requests = client.split_requests();
  curve.samples = sampler.finish(client.session(), curve.bytes, curve.payload);
  return curve;
}

}  // namespace pms::bench
