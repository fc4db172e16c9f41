// Land colours for the generated terrain: a palette picked by height and slope, blended across each band
// so no contour line shows. The bands are placed on the heights make_terrain produces (valley floors near
// 40 m, most of the land below 600 m, peaks up to 1500 m).
#include "io/terrain_colors.h"

#include <algorithm>
#include <cmath>

namespace pms {
namespace {

struct Rgb {
  float r, g, b;
};

constexpr Rgb kDeepWater{28, 66, 122}, kShallowWater{56, 112, 150}, kShore{186, 172, 124};
constexpr Rgb kLowGrass{62, 116, 42}, kHighGrass{112, 128, 62}, kRock{118, 108, 98}, kSnow{238, 241, 246};

constexpr float kWaterLevel = 48;    // metres: below it, water (the lowest valley floors)
constexpr float kShoreTop = 56;      // the shore band above the water
constexpr float kTreeline = 650;     // grass gives way to rock from here up ...
constexpr float kBareAbove = 900;    // ... and is gone above this
constexpr float kSnowLine = 950;     // snow starts here and covers gentle slopes fully ...
constexpr float kFullSnow = 1100;    // ... from this height up
constexpr float kSteep = 0.6f;       // slope (rise over run) where rock starts to show through grass
constexpr float kCliff = 1.0f;       // and where nothing else holds
constexpr float kSnowSlides = 1.2f;  // snow does not hold on slopes steeper than this

Rgb mix(Rgb a, Rgb b, float t) { return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t}; }

float ramp(float lo, float hi, float x) {
  const float t = std::clamp((x - lo) / (hi - lo), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

Rgb land_color(float height, float slope) {
  if (height < kWaterLevel) return mix(kDeepWater, kShallowWater, ramp(kWaterLevel - 10, kWaterLevel, height));
  const Rgb grass = mix(kLowGrass, kHighGrass, ramp(kShoreTop, kTreeline, height));
  Rgb ground = mix(kShore, grass, ramp(kWaterLevel, kShoreTop, height));
  const float bare = std::max(ramp(kTreeline, kBareAbove, height), ramp(kSteep, kCliff, slope));
  ground = mix(ground, kRock, bare);
  const float snow = ramp(kSnowLine, kFullSnow, height) * (1 - ramp(kCliff, kSnowSlides, slope));
  return mix(ground, kSnow, snow);
}

uint8_t channel(float value) { return uint8_t(std::clamp(value + 0.5f, 0.0f, 255.0f)); }

}  // namespace

void color_land(Mesh& m, uint32_t columns, uint32_t rows, float spacing) {
  m.colors.resize(4 * size_t(columns) * rows);
  const auto height = [&](uint32_t x, uint32_t y) { return m.positions[3 * (size_t(y) * columns + x) + 2]; };
  for (uint32_t y = 0; y < rows; ++y)
    for (uint32_t x = 0; x < columns; ++x) {
      // Central differences inside, one-sided on the border.
      const uint32_t x0 = x ? x - 1 : x, x1 = x + 1 < columns ? x + 1 : x;
      const uint32_t y0 = y ? y - 1 : y, y1 = y + 1 < rows ? y + 1 : y;
      const float dx = x1 > x0 ? (height(x1, y) - height(x0, y)) / (float(x1 - x0) * spacing) : 0;
      const float dy = y1 > y0 ? (height(x, y1) - height(x, y0)) / (float(y1 - y0) * spacing) : 0;
      const Rgb c = land_color(height(x, y), std::sqrt(dx * dx + dy * dy));
      uint8_t* out = &m.colors[4 * (size_t(y) * columns + x)];
      out[0] = channel(c.r);
      out[1] = channel(c.g);
      out[2] = channel(c.b);
      out[3] = 255;
    }
}

}  // namespace pms
