// Colours of the generated terrain (io/shapes.h, TerrainColors::land): land seen from the air.
#pragma once
#include <cstdint>

#include "io/mesh.h"

namespace pms {

// Fills `m.colors` (RGBA8, opaque) for a height field of `columns` x `rows` vertices stored row by row,
// `spacing` metres apart, heights in z: water on the valley floors, a shore, grass drying with height,
// rock on steep slopes and high up, snow on the high gentle slopes. A vertex's colour depends on its
// height and on its neighbours' (the slope), through + - * / and sqrt only: the same mesh gives the same
// colours bit for bit on every IEEE machine.
void color_land(Mesh& m, uint32_t columns, uint32_t rows, float spacing);

}  // namespace pms
