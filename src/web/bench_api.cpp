// The WASM module's entry for the bench (pmstream-bench --only web, bench/web/web_bench.mjs): the
// refinement engine's throughput inside the browser, measured by the same function the native bench
// calls (spm/path_refinement.h) over a .pms the page fetched, so the two builds' ops/s compare one to one.
// Only em++ compiles this file (web/CMakeLists.txt).
#include <emscripten/emscripten.h>

#include <exception>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "spm/path_refinement.h"
#include "spm/pms_file.h"
#include "web/view_probe.h"

namespace {

constexpr uint32_t kCameraFloats = 12;  // eye, target, up, fovy in degrees, width, height
std::string answer;                     // the last result, valid until the next call

}  // namespace

extern "C" {

// `pms`: a .pms file's bytes; `cameras`: `count` cameras of kCameraFloats each. JSON {ops, seconds, faces,
// frames} or {error}.
EMSCRIPTEN_KEEPALIVE const char* pms_bench_refine(const uint8_t* pms, uint32_t size, const float* cameras,
                                                  uint32_t count, float tolerance_px) {
  nlohmann::json out;
  try {
    const auto file = pms::PmsFile::from_bytes("bench.pms", pms, size);
    std::vector<pms::Camera> path;
    for (uint32_t i = 0; i < count; ++i) {
      const float* c = cameras + i * kCameraFloats;
      path.push_back(pms::web::camera_of(c, uint32_t(c[10]), uint32_t(c[11])));
    }
    const pms::PathRefinement run = pms::refine_along(file->model(), path, tolerance_px);
    out = {{"ops", run.ops}, {"seconds", run.seconds}, {"faces", run.faces}, {"frames", run.frames}};
  } catch (const std::exception& e) {
    out = {{"error", e.what()}};
  }
  answer = out.dump();
  return answer.c_str();
}

}  // extern "C"
