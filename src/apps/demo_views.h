// What the demo looks at and how: its flight, the page's first camera and the snapshots' light. A flat
// model (a terrain: the smallest box extent under a quarter of the others) is flown over like land; any
// other model is orbited.
#pragma once
#include <cstdint>
#include <vector>

#include "common/camera.h"
#include "render/render.h"
#include "spm/hierarchy.h"

namespace pms::app {

// The headless flight: over a flat model low across it, looking ahead and down; else the orbit path.
std::vector<Camera> demo_flight_path(const ModelData& model, uint32_t frames);

// The page's first camera: over a flat model from beyond its near edge, above its highest point, looking
// across it (land, its ranges and the sky in one picture); else the orbit's first camera.
Camera demo_first_view(const ModelData& model);

// The snapshots' look: over a flat model a sky behind and a low sun; else the renderer's headlight.
RenderOptions demo_snapshot_look(const ModelData& model);

}  // namespace pms::app
