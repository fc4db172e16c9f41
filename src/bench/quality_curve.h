// E6's measurement (kim-lee-kobbelt Fig. 10; cheng-ooi Fig. 8): the image quality of a streaming client's
// mesh as a function of the bytes it has received, while it streams toward one view from the base mesh.
// The client is the real one of each mode; at byte counts spaced geometrically it renders the mesh it would
// show with what it holds then (a mode that refines itself adapts it first; one that applies splits as they
// come shows its mesh as it is) against the full model's image at the same camera.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "bench/bench_model.h"
#include "client/receiver_client.h"
#include "common/camera.h"
#include "protocol/stream_mode.h"
#include "render/render.h"
#include "spm/selective_mesh.h"

namespace pms::bench {

struct CurveSample {
  uint64_t bytes = 0;    // received so far as counted on the wire: whole frames, or HTTP with its headers
  uint64_t payload = 0;  // the same without the framing (frame headers, HTTP status lines and headers)
  uint64_t faces = 0;
  double psnr = 0;  // against the full model's image (+infinity when identical)
  uint64_t error_pixels = 0;
};

struct QualityCurve {
  std::vector<CurveSample> samples;  // bytes strictly increasing; the first is the base mesh, the last the final one
  uint64_t splits = 0;               // the client's count of splits received
  uint64_t requests = 0;             // receiver-driven: GETs of split ids
  uint64_t bytes = 0, payload = 0;   // the client's own counters after the view (equal to the last sample's)
};

// The full model's image at one camera, which every sample is compared with.
struct QualityTarget {
  ViewParams view;
  Image reference;
};
QualityTarget quality_target(const ModelData& model, const MeshArrays& full, const Camera& camera, Renderer& renderer);

// Each sample after the first waits until the bytes received have grown by this factor.
constexpr double kCurveSampleGrowth = 1.12;

// A StreamingClient in `mode` over an in-process session of `m` (deterministic, no sockets): OPEN, BASE, then
// one frame at `camera` and `tolerance_px`.
QualityCurve session_curve(const BenchModel& m, protocol::StreamMode mode, const Camera& camera, float tolerance_px,
                           const QualityTarget& target, Renderer& renderer);

// A ReceiverClient against `pmstream serve --http-port` on loopback `http_port`: GET /models, the base and
// code tables, then one frame at `camera` and `tolerance_px`; with `ranking` area (the plain records),
// stopping at `stop_area` pixels instead of τ.
QualityCurve receiver_curve(uint16_t http_port, const std::string& model, const Camera& camera, float tolerance_px,
                            const QualityTarget& target, Renderer& renderer,
                            client::Ranking ranking = client::Ranking::error, uint32_t stop_area = 1);

}  // namespace pms::bench
