// The link `pmstream demo` prints (docs/web.md, "The link"): the model escaped, and a camera that reads back
// bit for bit, so the page opens exactly on the view the demo picked.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "apps/demo_serve.h"

namespace pms {
namespace {

TEST(DemoLink, CarriesModelModeToleranceAndCamera) {
  Camera camera;
  camera.eye[0] = 500, camera.eye[1] = 4990.876f, camera.eye[2] = 2303.3494f;
  camera.target[0] = 2000, camera.target[1] = 0.1f, camera.target[2] = -770.25f;
  camera.up[0] = 0, camera.up[1] = 0, camera.up[2] = 1;
  camera.fovy_deg = 50;
  EXPECT_EQ(app::page_link(7301, "terrain", camera, 1),
            "http://127.0.0.1:7301/#model=terrain&mode=sender&tau=1&eye=500,4990.876,2303.3494"
            "&target=2000,0.1,-770.25&up=0,0,1&fovy=50");
  EXPECT_NE(app::page_link(7301, "my scan&v2", camera, 0.5f).find("#model=my%20scan%26v2&mode=sender&tau=0.5&"),
            std::string::npos);
}

TEST(DemoLink, NumbersReadBackBitForBit) {
  Camera camera;
  const float awkward[3] = {1.0f / 3, -123456.789f, 6.02e-7f};
  for (int k = 0; k < 3; ++k) camera.eye[k] = awkward[k];
  const std::string link = app::page_link(1, "m", camera, 1);
  const size_t at = link.find("&eye=") + 5;
  char* end = nullptr;
  const char* text = link.c_str() + at;
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(std::strtof(text, &end), awkward[k]) << link;
    text = end + 1;  // past the comma
  }
}

}  // namespace
}  // namespace pms
