#include "client/multilevel_viewer.h"

namespace pms::client {

// Free-running: the levels load in the background and no frame waits (MultilevelOptions::free_running).
MultilevelOptions paced(MultilevelOptions options, Pacing pacing) {
  options.free_running = pacing == Pacing::free_running;
  return options;
}

MultilevelViewer::MultilevelViewer(std::unique_ptr<HttpTransport> http, const MultilevelOptions& options,
                                   const std::string& model)
    : client_(std::move(http), paced(options, Pacing::free_running)), options_(paced(options, Pacing::free_running)) {
  client_.start_open(model);
}

ViewerReport MultilevelViewer::frame_view(const Camera& camera) {
  if (!client_.poll_open()) return opening_report();
  const MultilevelFrame r = client_.frame(camera);
  if (!client_.opened()) return opening_report();  // a 410: the model's new version opens
  ViewerReport report;
  report.frame = r.report.frame;
  report.faces = r.report.faces;
  report.vertices = client_.lod().vertex_count();
  report.received = r.report.vsplits;  // levels
  report.up_bytes = r.report.up_bytes;
  report.down_bytes = r.report.down_bytes;
  report.latency_ms = r.report.latency_ms;
  report.in_flight = r.in_flight;
  report.satisfied = client_.loader().finest_loaded() <= r.wanted_level;
  report.details = {{"down_payload_bytes", r.payload_down},
                    {"wanted_level", r.wanted_level},
                    {"level", r.level},
                    {"levels_loaded", r.levels_loaded},
                    {"lod_ms", r.lod_ms}};
  return report;
}

void MultilevelViewer::retune(const ViewerTuning& tuning) {
  if (tuning.tolerance) options_.tolerance = *tuning.tolerance;
  if (tuning.lod_budget) options_.budget = *tuning.lod_budget;
  if (tuning.morph_frames) options_.morph_frames = *tuning.morph_frames;
  client_.set_rule(options_.tolerance, options_.budget, options_.morph_frames);
}

nlohmann::json MultilevelViewer::totals() const {
  nlohmann::json arrivals = nlohmann::json::array();
  for (const LevelArrival& a : client_.arrivals())
    arrivals.push_back({{"level", a.level},
                        {"bytes", a.bytes},
                        {"down_bytes", a.down_bytes},
                        {"down_payload_bytes", a.payload_down},
                        {"ms", a.ms}});
  const HttpCounters& c = client_.counters();
  nlohmann::json out = {{"total_down_payload_bytes", c.payload_down},
                        {"http_requests", c.requests},
                        {"http_connections", c.connections},
                        {"reopens", client_.reopens()},
                        {"rule", options_.budget ? "budget" : "screen"},
                        {"form", options_.compressed ? "compressed" : "plain"},
                        {"levels", client_.opened() ? client_.loader().level_count() : 0},
                        {"levels_received", client_.arrivals().size()},
                        {"arrivals", arrivals}};
  if (!client_.arrivals().empty()) {
    const LevelArrival& first = client_.arrivals().front();
    out["first_picture_ms"] = first.ms;
    out["first_picture_bytes"] = first.down_bytes;
    out["first_picture_payload_bytes"] = first.payload_down;
  }
  return out;
}

}  // namespace pms::client
