#include "image/image_encoding.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <limits>

namespace nephele {
namespace {

FloatImage gradientImage(int w, int h) {
  FloatImage image{w, h, std::vector<float>(std::size_t(w) * h * 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = image.pixel(x, y);
      p[0] = float(x) / w;
      p[1] = float(y) / h;
      p[2] = 0.25f;
      p[3] = float(x + y) / (w + h);
    }
  return image;
}

class ImageEncodingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        std::filesystem::temp_directory_path() / ("nephele_encoding_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;
};

TEST_F(ImageEncodingTest, FormatFollowsExtension) {
  EXPECT_EQ(imageFileFormatForPath("a.PNG"), ImageFileFormat::kPng);
  EXPECT_EQ(imageFileFormatForPath("a.jpeg"), ImageFileFormat::kJpeg);
  EXPECT_EQ(imageFileFormatForPath("dir.x/a.tif"), ImageFileFormat::kTiff);
  EXPECT_EQ(imageFileFormatForPath("a.exr"), ImageFileFormat::kExr);
  EXPECT_EQ(imageFileFormatForPath("a.bmp"), std::nullopt);
  EXPECT_EQ(imageFileFormatForPath("noextension"), std::nullopt);
}

TEST_F(ImageEncodingTest, PngHoldsSrgbBytesTopRowFirst) {
  const FloatImage image = gradientImage(16, 8);
  ASSERT_EQ(writeImageFile(path("a.png"), image), "");
  auto in = OIIO::ImageInput::open(path("a.png"));
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().nchannels, 3);
  EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT8);
  std::vector<std::uint8_t> bytes(16 * 8 * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, bytes.data()));
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(bytes[(y * 16 + x) * 3 + c], toByte(srgbEncode(image.pixel(x, y)[c])));
}

TEST_F(ImageEncodingTest, BottomUpRowsAreWrittenTopDown) {
  Srgb8Image image{2, 2, true, {10, 0, 0, 255, 20, 0, 0, 255, 30, 0, 0, 255, 40, 0, 0, 255}};
  ASSERT_EQ(writeImageFile(path("b.png"), image), "");
  auto in = OIIO::ImageInput::open(path("b.png"));
  ASSERT_TRUE(in);
  std::vector<std::uint8_t> bytes(2 * 2 * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, bytes.data()));
  EXPECT_EQ(bytes[0], 30);  // the stored last row is the top row
  EXPECT_EQ(bytes[6], 10);
}

TEST_F(ImageEncodingTest, ExrHoldsLinearRgbAndCoverage) {
  const FloatImage image = gradientImage(12, 10);
  for (bool half : {true, false}) {
    EncodeOptions options;
    options.exr_half = half;
    options.exr_compression = half ? "piz" : "none";
    ASSERT_EQ(writeImageFile(path("a.exr"), image, options), "");
    auto in = OIIO::ImageInput::open(path("a.exr"));
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().nchannels, 4);
    EXPECT_EQ(in->spec().alpha_channel, 3);
    EXPECT_EQ(in->spec().format, half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
    std::vector<float> values(image.rgba.size());
    ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::FLOAT, values.data()));
    for (std::size_t i = 0; i < values.size(); ++i)
      ASSERT_NEAR(values[i], image.rgba[i], half ? 1e-3 : 0.0);
  }
}

TEST_F(ImageEncodingTest, JpegAndTiffAreWritten) {
  const FloatImage image = gradientImage(32, 16);
  for (const char* name : {"a.jpg", "a.tiff"}) {
    ASSERT_EQ(writeImageFile(path(name), image), "");
    auto in = OIIO::ImageInput::open(path(name));
    ASSERT_TRUE(in) << name;
    EXPECT_EQ(in->spec().width, 32);
    EXPECT_EQ(in->spec().nchannels, 3);
  }
}

TEST_F(ImageEncodingTest, FailuresLeaveNoFile) {
  const FloatImage image = gradientImage(4, 4);
  EXPECT_NE(writeImageFile(path("a.bmp"), image).find("allowed: .png"), std::string::npos);
  EXPECT_NE(writeImageFile(path("missing/dir/a.png"), image), "");
  Srgb8Image bytes{1, 1, false, {0, 0, 0, 0}};
  EXPECT_NE(writeImageFile(path("a.exr"), bytes).find("float"), std::string::npos);
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
}

}  // namespace
// toSrgb8 finds bytes in a table of thresholds; it must round as the formula does.
TEST(ImageEncoding, TableSrgbEqualsTheFormula) {
  FloatImage image{1000, 1, std::vector<float>(4000, 0.0f)};
  for (int i = 0; i < 1000; ++i)
    image.rgba[i * 4] = i < 990 ? float(std::pow(i / 989.0, 2.2)) * 1.01f : float(i - 995) * 0.5f;
  image.rgba[4 * 999 + 1] = std::nanf("");
  const Srgb8Image bytes = toSrgb8(image);
  int differing = 0;
  for (int i = 0; i < 1000; ++i)
    for (int c = 0; c < 3; ++c)
      differing += bytes.rgba[i * 4 + c] != toByte(srgbEncode(image.rgba[i * 4 + c]));
  EXPECT_EQ(differing, 0);
}

// Every 61st float from 2^-20 to 2 (1.9 million, every bucket of the byte table and both
// sides of every threshold many times over) encodes as the formula does.
TEST(ImageEncoding, TableSrgbEqualsTheFormulaAcrossTheFloats) {
  const std::uint32_t from = std::bit_cast<std::uint32_t>(std::ldexp(1.0f, -20));
  const std::uint32_t to = std::bit_cast<std::uint32_t>(2.0f);
  FloatImage image{0, 1, {}};
  for (std::uint32_t bits = from; bits <= to; bits += 61) {
    image.rgba.insert(image.rgba.end(), {std::bit_cast<float>(bits), 0.0f, 0.0f, 1.0f});
    ++image.width;
  }
  const Srgb8Image bytes = toSrgb8(image);
  int differing = 0;
  for (int i = 0; i < image.width; ++i)
    differing +=
        bytes.rgba[std::size_t(i) * 4] != toByte(srgbEncode(image.rgba[std::size_t(i) * 4]));
  EXPECT_EQ(differing, 0) << "of " << image.width;
}

// Every finite half comes back from its own value, and the floats between two neighbours go
// to the nearer, ties to the one with an even mantissa, the halves decoded here from their
// fields (sign, 5 exponent bits biased by 15, 10 mantissa bits; subnormal below 2^-14).
TEST(ImageEncoding, HalfFloatBitsRoundToTheNearestHalf) {
  auto value = [](std::uint32_t h) {
    const int exponent = int(h >> 10) & 31, mantissa = int(h & 1023);
    const double magnitude = exponent == 0 ? std::ldexp(double(mantissa), -24)
                                           : std::ldexp(1.0 + mantissa / 1024.0, exponent - 15);
    return (h & 0x8000u) ? -magnitude : magnitude;
  };
  int wrong = 0;
  for (std::uint32_t h = 0; h < 0x10000u; ++h) {
    if (((h >> 10) & 31) == 31) continue;  // infinities and NaNs, below
    wrong += halfFloatBits(float(value(h))) != h;
    if ((h & 0x7fffu) == 0x7bffu) continue;  // the largest: its upper neighbour is infinity
    const float mid = float(0.5 * (value(h) + value(h + 1)));  // exact: 12 bits of mantissa
    const float towards_h = std::nextafter(mid, float(value(h)));
    const float away = std::nextafter(mid, float(value(h + 1)));
    wrong += halfFloatBits(towards_h) != h;
    wrong += halfFloatBits(away) != h + 1;
    wrong += halfFloatBits(mid) != ((h & 1u) ? h + 1 : h);
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(halfFloatBits(65519.0f), 0x7bffu);  // the largest half, 65504, is nearest
  EXPECT_EQ(halfFloatBits(65520.0f), 0x7c00u);  // the tie goes to the even: infinity
  EXPECT_EQ(halfFloatBits(-1.0e9f), 0xfc00u);
  EXPECT_EQ(halfFloatBits(std::numeric_limits<float>::infinity()), 0x7c00u);
  const std::uint16_t nan = halfFloatBits(std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(nan & 0x7c00u, 0x7c00u);
  EXPECT_NE(nan & 0x3ffu, 0u);
  EXPECT_EQ(halfFloatBits(1.0e-9f), 0u);  // under half the smallest subnormal
  EXPECT_EQ(halfFloatBits(-0.0f), 0x8000u);
}

}  // namespace nephele
