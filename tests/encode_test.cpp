#include "renderer/encode.h"

#include <gtest/gtest.h>

#include <cstring>

namespace nephele {
namespace {

// A 2x1 frame with colour, coverage and depth, each value distinct.
Frame smallFrame() {
  Frame f;
  f.info.width = 2;
  f.info.height = 1;
  f.channels = {Channel::kColour, Channel::kCoverage, Channel::kDepth};
  f.colour = {2, 1, {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f}};
  f.depth = {100.0f, 200.0f};
  return f;
}

std::vector<float> asFloats(const std::vector<std::uint8_t>& bytes) {
  std::vector<float> out(bytes.size() / sizeof(float));
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

TEST(Encode, RawFloatPlanesFollowTheAskedOrder) {
  const Channels channels{{Channel::kDepth, Channel::kColour, Channel::kCoverage},
                          Channels::Pixels::kPlanes};
  const Encoded encoded = encode(smallFrame(), ImageFileFormat::kRaw, channels);
  ASSERT_TRUE(std::holds_alternative<std::vector<std::uint8_t>>(encoded));
  EXPECT_EQ(asFloats(std::get<std::vector<std::uint8_t>>(encoded)),
            (std::vector<float>{100, 200, 0.1f, 0.5f, 0.2f, 0.6f, 0.3f, 0.7f, 0.4f, 0.8f}));
}

TEST(Encode, Raw8BitIsColourThenCoverageWhateverTheOrder) {
  Frame f = smallFrame();
  f.srgb = {2, 1, false, {1, 2, 3, 4, 5, 6, 7, 8}};
  const Channels channels{{Channel::kCoverage, Channel::kColour}, Channels::Pixels::kSrgb8};
  const Encoded encoded = encode(f, ImageFileFormat::kRaw, channels);
  ASSERT_TRUE(std::holds_alternative<std::vector<std::uint8_t>>(encoded));
  EXPECT_EQ(std::get<std::vector<std::uint8_t>>(encoded),
            (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6, 7, 8}));
  const Channels alpha{{Channel::kCoverage}, Channels::Pixels::kSrgb8};
  EXPECT_EQ(std::get<std::vector<std::uint8_t>>(encode(f, ImageFileFormat::kRaw, alpha)),
            (std::vector<std::uint8_t>{4, 8}));
}

TEST(Encode, EightBitPixelsComeFromFloatsWhenTheFrameHasNone) {
  const Frame f = smallFrame();
  const Channels colour{{Channel::kColour}, Channels::Pixels::kSrgb8};
  const Srgb8Image expected = toSrgb8(f.colour);
  EXPECT_EQ(std::get<std::vector<std::uint8_t>>(encode(f, ImageFileFormat::kRaw, colour)),
            (std::vector<std::uint8_t>{expected.rgba[0], expected.rgba[1], expected.rgba[2],
                                       expected.rgba[4], expected.rgba[5], expected.rgba[6]}));
}

TEST(Encode, PixelsAFormatCannotHoldAreAnError) {
  const Frame f = smallFrame();
  const Channels linear{{Channel::kColour}, Channels::Pixels::kLinear};
  const Channels planes = Channels::planesOf(f.channels);
  const Channels srgb{{Channel::kColour}, Channels::Pixels::kSrgb8};
  EXPECT_TRUE(std::holds_alternative<std::string>(encode(f, ImageFileFormat::kPng, linear)));
  EXPECT_TRUE(std::holds_alternative<std::string>(encode(f, ImageFileFormat::kPng, planes)));
  EXPECT_TRUE(std::holds_alternative<std::string>(encode(f, ImageFileFormat::kExr, srgb)));
  EXPECT_NE(writeImage("frame.bmp", f, srgb).find("allowed: .png"), std::string::npos);
}

TEST(Encode, ExrOfPlanesCarriesThePoseAndLinearExrDoesNot) {
  Frame f = smallFrame();
  f.info.time_s = 86400.0;  // 1970:01:02 00:00:00
  const auto planes = std::get<std::vector<std::uint8_t>>(
      encode(f, ImageFileFormat::kExr, Channels::planesOf(f.channels)));
  const auto linear = std::get<std::vector<std::uint8_t>>(
      encode(f, ImageFileFormat::kExr,
             {{Channel::kColour, Channel::kCoverage}, Channels::Pixels::kLinear}));
  const auto holds = [](const std::vector<std::uint8_t>& bytes, const std::string& text) {
    return std::search(bytes.begin(), bytes.end(), text.begin(), text.end()) != bytes.end();
  };
  EXPECT_TRUE(holds(planes, "nephele:focal_px"));
  EXPECT_TRUE(holds(planes, "1970:01:02 00:00:00"));
  EXPECT_TRUE(holds(planes, "depth"));
  EXPECT_FALSE(holds(linear, "nephele:focal_px"));
  EXPECT_FALSE(holds(linear, "depth"));
}

}  // namespace
}  // namespace nephele
