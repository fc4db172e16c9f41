#include "client/receiver_viewer.h"

namespace pms::client {

// Free-running: each frame attaches what has arrived and returns (ReceiverOptions::free_running).
ReceiverOptions paced(ReceiverOptions options, Pacing pacing) {
  options.free_running = pacing == Pacing::free_running;
  return options;
}

ReceiverViewer::ReceiverViewer(std::unique_ptr<HttpTransport> http, std::unique_ptr<ImportanceSource> importance,
                               const ReceiverOptions& options, const std::string& model)
    : client_(std::move(http), std::move(importance), paced(options, Pacing::free_running)),
      options_(paced(options, Pacing::free_running)) {
  client_.start_open(model);
}

void ReceiverViewer::retune(const ViewerTuning& tuning) {
  if (tuning.tolerance) options_.tolerance = *tuning.tolerance;
  if (tuning.morph_frames) options_.morph_frames = *tuning.morph_frames;
  if (tuning.prefetch) options_.prefetch = *tuning.prefetch;
  if (tuning.background_bytes) options_.background_bytes = *tuning.background_bytes;
  client_.set_view_options(options_);
}

ViewerReport ReceiverViewer::frame_view(const Camera& camera) {
  if (!client_.poll_open()) return opening_report();
  const ReceiverFrame r = client_.frame(camera);
  if (!client_.session().has_model()) return opening_report();  // a 410: the model's new version opens
  unsatisfied_ += !r.satisfied;
  ViewerReport report;
  report.frame = r.report.frame;
  report.faces = r.report.faces;
  report.vertices = client_.session().mesh().vertex_count();
  report.received = r.report.vsplits;
  report.up_bytes = r.report.up_bytes;
  report.down_bytes = r.report.down_bytes;
  report.latency_ms = r.report.latency_ms;
  report.in_flight = r.in_flight;
  report.satisfied = r.satisfied;
  report.details = {{"down_payload_bytes", r.payload_down},
                    {"split_requests", r.split_requests},
                    {"cache_hits", r.cache_hits},
                    {"rounds", r.rounds},
                    {"rankings", r.rankings},
                    {"satisfied", r.satisfied},
                    {"queued", r.queued},
                    {"in_flight", r.in_flight},
                    {"cancelled", r.cancelled},
                    {"stale_arrivals", r.stale_arrivals},
                    {"prefetched", r.prefetched},
                    {"prefetch_used", r.prefetch_used},
                    {"background", r.background}};
  return report;
}

Mesh ReceiverViewer::mesh() const {
  return client_.session().has_model() ? current_mesh(client_.session().refinement()) : Mesh{};
}

ViewParams ReceiverViewer::view_params(const Camera& camera) const { return client_.session().view_params(camera); }

uint64_t ReceiverViewer::received_total() const { return client_.session().splits_received(); }

nlohmann::json ReceiverViewer::totals() const {
  const HttpCounters& c = client_.counters();
  const ReceiverTotals& t = client_.totals();
  return {{"total_down_payload_bytes", c.payload_down},
          {"http_requests", c.requests},
          {"split_requests", t.split_requests},
          {"requested_ids", t.requested_ids},
          {"request_code_bytes", t.request_code_bytes},
          {"cache_hits", t.cache_hits},
          {"frames_unsatisfied", unsatisfied_},
          {"settle_frames", client_.settle_frames()},
          {"cancelled", t.cancelled},
          {"stale_arrivals", t.stale_arrivals},
          {"prefetched", t.prefetched},
          {"prefetch_used", t.prefetch_used},
          {"rankings", t.rankings},
          {"background_ids", t.background_ids},
          {"background_bytes", t.background_bytes},
          {"http_connections", c.connections},
          {"reopens", client_.reopens()},
          {"fetch", fetch_policy_name(options_.fetch)},
          {"frame_budget_ms", options_.frame_budget_ms},
          {"frame_answers", options_.frame_answers},
          {"prefetch", options_.prefetch},
          {"rerank_ms", options_.rerank_ms},
          {"background_budget_bytes", options_.background_bytes}};
}

}  // namespace pms::client
