// Image files as the coordinator writes them, read back by OpenImageIO:
// EXR and PNG by their own libraries, HDR, TIFF and JPEG through the
// module loaded on demand (common/image/image_writer.h), all beside the
// programs in bin/ where this test binary lives too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "common/image/image_reader.h"
#include "common/image/image_writer.h"
#include "common/util/temporary_directory.h"

namespace portico {
namespace {

namespace fs = std::filesystem;

LinearImage gradient(uint32_t width, uint32_t height) {
  LinearImage image{width, height, std::vector<float>(size_t(width) * height * 3)};
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        image.rgb[(size_t(y) * width + x) * 3 + c] = 0.9f * float(x + y * 2 + c) / float(width + height * 2 + 2);
  return image;
}

TEST(ImageFiles, LinearFormatsKeepRadianceExactlyAndLeaveNoTemporaryFile) {
  TemporaryDirectory dir("portico-image-files");
  const LinearImage image = gradient(37, 21);
  for (const char* name : {"a.exr", "b.tif", "c.hdr"}) {
    const fs::path path = dir.path() / name;
    writeImage(path.string(), image);
    const LinearImage back = readImage(path.string());
    ASSERT_EQ(back.width, image.width) << name;
    ASSERT_EQ(back.height, image.height) << name;
    // RGBE: 8-bit mantissas under the pixel's largest component's exponent.
    const bool rgbe = fs::path(name).extension() == ".hdr";
    for (size_t i = 0; i < image.rgb.size(); ++i) {
      const size_t pixel = i / 3 * 3;
      const float largest = std::max({image.rgb[pixel], image.rgb[pixel + 1], image.rgb[pixel + 2]});
      if (rgbe)
        ASSERT_NEAR(back.rgb[i], image.rgb[i], largest / 128.0f) << name << " value " << i;
      else
        ASSERT_EQ(back.rgb[i], image.rgb[i]) << name << " value " << i;
    }
    fs::remove(path);
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(ImageFiles, EightBitFormatsAreToneMappedWithTheExposure) {
  TemporaryDirectory dir("portico-image-files");
  const LinearImage image = gradient(16, 9);
  const float exposure = 1.5f;
  const fs::path png = dir.path() / "a.png", jpg = dir.path() / "b.jpg";
  writeImage(png.string(), image, exposure);
  writeImage(jpg.string(), image, exposure);
  const LinearImage fromPng = readImage(png.string()), fromJpg = readImage(jpg.string());
  ASSERT_EQ(fromPng.width, 16u);
  ASSERT_EQ(fromJpg.height, 9u);
  double jpegError = 0;
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    const uint8_t byte = toneMapToByte(image.rgb[i], exposure);
    ASSERT_EQ(std::lround(fromPng.rgb[i] * 255.0f), byte) << "png value " << i;   // lossless
    const float expected = float(byte) / 255.0f;
    jpegError += std::abs(fromJpg.rgb[i] - expected);
  }
  EXPECT_LT(jpegError / double(image.rgb.size()), 0.03);   // lossy, but the same picture
}

TEST(ImageFiles, AFailedWriteNamesTheFileAndLeavesNothing) {
  TemporaryDirectory dir("portico-image-files");
  const LinearImage image = gradient(4, 4);
  for (const char* name : {"gone/a.exr", "gone/a.png", "gone/a.tif"}) {
    const fs::path path = dir.path() / name;
    try {
      writeImage(path.string(), image);
      ADD_FAILURE() << name << " was written into a missing directory";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find(".tmp-"), std::string::npos) << e.what();
    }
  }
  LinearImage wrong = image;
  wrong.rgb.pop_back();
  EXPECT_THROW(writeImage((dir.path() / "short.exr").string(), wrong), std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace portico
