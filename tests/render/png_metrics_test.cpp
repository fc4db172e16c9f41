// PNG output read back with libpng, and the cheng-ooi Table 2 metrics on hand-made images.
#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <filesystem>

#include "common/error.h"
#include "render/render.h"
#include "test_support.h"

namespace pms {
namespace {

Image solid(uint32_t width, uint32_t height, uint8_t r, uint8_t g, uint8_t b) {
  Image image;
  image.width = width, image.height = height;
  image.rgb.resize(3 * size_t(width) * height);
  for (size_t p = 0; p < size_t(width) * height; ++p) {
    image.rgb[3 * p] = r;
    image.rgb[3 * p + 1] = g;
    image.rgb[3 * p + 2] = b;
  }
  return image;
}

TEST(Png, RoundTripThroughLibpng) {
  Image image;
  image.width = 7, image.height = 5;  // odd sizes: no row padding assumptions
  for (uint32_t y = 0; y < image.height; ++y)
    for (uint32_t x = 0; x < image.width; ++x) {
      image.rgb.push_back(uint8_t(x * 30));
      image.rgb.push_back(uint8_t(y * 50));
      image.rgb.push_back(uint8_t(x * y + 1));
    }
  const std::string path = (test::temp_dir() / "image.png").string();
  save_png(path, image);

  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&png, path.c_str())) << png.message;
  EXPECT_EQ(png.width, image.width);
  EXPECT_EQ(png.height, image.height);
  EXPECT_EQ(PNG_IMAGE_SAMPLE_CHANNELS(png.format), 3u);
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(png));
  ASSERT_TRUE(png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr)) << png.message;
  EXPECT_EQ(pixels, image.rgb);
}

TEST(Png, WriteFailureNamesTheFile) {
  const std::string path = (test::temp_dir() / "no-such-dir" / "image.png").string();
  try {
    save_png(path, solid(2, 2, 1, 2, 3));
    FAIL() << "expected pms::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_THROW(save_png((test::temp_dir() / "empty.png").string(), Image{}), Error);
}

TEST(Metrics, IdenticalImages) {
  const ImageMetrics m = compare_images(solid(4, 3, 9, 9, 9), solid(4, 3, 9, 9, 9));
  EXPECT_TRUE(std::isinf(m.psnr) && m.psnr > 0);
  EXPECT_EQ(m.error_pixels, 0u);
  EXPECT_EQ(m.error_fraction, 0.0);
}

TEST(Metrics, HandComputedValues) {
  // 2x2 images, one pixel off by 10 in red: MSE = 100 / (3 * 4), PSNR = 10 log10(255^2 * 12 / 100).
  Image a = solid(2, 2, 100, 100, 100), b = a;
  b.rgb[3 * 3 + 0] = 110;
  ImageMetrics m = compare_images(a, b);
  EXPECT_NEAR(m.psnr, 10 * std::log10(255.0 * 255.0 * 12 / 100), 1e-9);
  EXPECT_NEAR(m.psnr, 38.9226, 1e-4);
  EXPECT_EQ(m.error_pixels, 1u);
  EXPECT_DOUBLE_EQ(m.error_fraction, 0.25);

  // A difference of 1 in one channel is an error pixel (exact comparison); two channels of one pixel
  // still count once.
  b.rgb[3 * 1 + 1] = 101;
  b.rgb[3 * 1 + 2] = 99;
  m = compare_images(a, b);
  EXPECT_EQ(m.error_pixels, 2u);
  EXPECT_DOUBLE_EQ(m.error_fraction, 0.5);
  EXPECT_NEAR(m.psnr, 10 * std::log10(255.0 * 255.0 * 12 / 102), 1e-9);

  // Black against white everywhere: MSE = 255^2, PSNR = 0 dB.
  m = compare_images(solid(3, 3, 0, 0, 0), solid(3, 3, 255, 255, 255));
  EXPECT_NEAR(m.psnr, 0.0, 1e-12);
  EXPECT_EQ(m.error_pixels, 9u);
  EXPECT_DOUBLE_EQ(m.error_fraction, 1.0);
}

TEST(Metrics, SizesMustMatch) { EXPECT_THROW(compare_images(solid(2, 2, 0, 0, 0), solid(2, 3, 0, 0, 0)), Error); }

}  // namespace
}  // namespace pms
