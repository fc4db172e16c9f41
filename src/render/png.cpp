// PNG output through libpng's simplified API (png_image, libpng >= 1.6): no setjmp/longjmp crosses
// C++ frames, and failures come back as a message we can put after the file name.
#include <png.h>

#include "common/error.h"
#include "render/render.h"

namespace pms {

void save_png(const std::string& path, const Image& image) {
  if (image.width == 0 || image.height == 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
    fail(path, "cannot write PNG: the image is empty or its buffer has the wrong size");
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = image.width;
  png.height = image.height;
  png.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&png, path.c_str(), 0, image.rgb.data(), png_int_32(3 * image.width), nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    fail(path, "cannot write PNG: " + message);
  }
}

}  // namespace pms
