#include "renderer/encode.h"

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

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

// The pixels of encoded bytes as OpenImageIO decodes them, `channels` per pixel as T; the
// channel names of the file in `names`.
template <typename T>
std::vector<T> decoded(const Encoded& encoded, const char* extension, int channels,
                       std::vector<std::string>* names = nullptr) {
  const auto* bytes = std::get_if<std::vector<std::uint8_t>>(&encoded);
  if (!bytes) {
    ADD_FAILURE() << std::get<std::string>(encoded);
    return {};
  }
  // A file of this test's own: ctest runs the tests of this binary side by side.
  const std::string path = testing::TempDir() + "encode_test_" +
                           testing::UnitTest::GetInstance()->current_test_info()->name() +
                           extension;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes->data()), std::streamsize(bytes->size()));
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    ADD_FAILURE() << OIIO::geterror();
    return {};
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (names) *names = spec.channelnames;
  EXPECT_EQ(spec.nchannels, channels);
  std::vector<T> out(std::size_t(spec.width) * spec.height * channels);
  const auto type = std::is_same_v<T, float>           ? OIIO::TypeDesc::FLOAT
                    : std::is_same_v<T, std::uint16_t> ? OIIO::TypeDesc::UINT16
                                                       : OIIO::TypeDesc::UINT8;
  EXPECT_TRUE(in->read_image(0, 0, 0, channels, type, out.data()));
  std::filesystem::remove(path);
  return out;
}

// A 3x2 frame with an lwir channel and a derived plane of brightness temperatures.
Frame greyFrame() {
  Frame f;
  f.info.width = 3;
  f.info.height = 2;
  f.channels = {Channel::kLwir};
  f.lwir = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f};
  f.derived.push_back({"kelvin", {210.0f, 220.0f, 245.3f, 270.0f, 319.9f, 340.0f}});
  f.derived.push_back({"mask", {0.0f, 1.0f, 2.4f, 65535.0f, 70000.0f, -3.0f}});
  return f;
}

TEST(Encode, Grey8PngShowsThePlaneFromLowToHighInEveryColourByte) {
  const Frame f = greyFrame();
  Channels grey{{}, Channels::Pixels::kGrey8, {"kelvin"}};
  grey.grey_lo = 220.0;
  grey.grey_hi = 320.0;
  const std::vector<std::uint8_t> rgb =
      decoded<std::uint8_t>(encode(f, ImageFileFormat::kPng, grey), ".png", 3);
  ASSERT_EQ(rgb.size(), 18u);
  const std::vector<float>& kelvin = f.derived[0].values;
  for (std::size_t i = 0; i < kelvin.size(); ++i) {
    const double unit = std::min(1.0, std::max(0.0, (kelvin[i] - 220.0) / 100.0));
    const auto expected = std::uint8_t(std::floor(unit * 255.0 + 0.5));
    for (int k = 0; k < 3; ++k) EXPECT_EQ(rgb[i * 3 + k], expected) << i << " " << k;
  }
  // A channel's plane is grey too; two planes are not.
  const Channels lwir{{Channel::kLwir}, Channels::Pixels::kGrey8};
  const std::vector<std::uint8_t> raw =
      std::get<std::vector<std::uint8_t>>(encode(f, ImageFileFormat::kRaw, lwir));
  EXPECT_EQ(raw[0], 255);  // 1 W m^-2 sr^-1 against the range 0..1
  EXPECT_TRUE(std::holds_alternative<std::string>(
      encode(f, ImageFileFormat::kPng, {{Channel::kLwir}, Channels::Pixels::kGrey8, {"kelvin"}})));
}

TEST(Encode, Grey16PngHoldsThePlanesIntegers) {
  const Frame f = greyFrame();
  const Channels mask{{}, Channels::Pixels::kGrey16, {"mask"}};
  EXPECT_EQ(decoded<std::uint16_t>(encode(f, ImageFileFormat::kPng, mask), ".png", 1),
            (std::vector<std::uint16_t>{0, 1, 2, 65535, 65535, 0}));
  EXPECT_TRUE(std::holds_alternative<std::string>(encode(f, ImageFileFormat::kTiff, mask)));
  EXPECT_TRUE(std::holds_alternative<std::string>(
      encode(f, ImageFileFormat::kPng, {{}, Channels::Pixels::kGrey16, {"absent"}})));
}

TEST(Encode, DerivedPlanesFollowTheChannelsAsFloatPlanes) {
  const Frame f = greyFrame();
  const Channels planes{{Channel::kLwir}, Channels::Pixels::kPlanes, {"kelvin"}};
  std::vector<float> expected = f.lwir;
  expected.insert(expected.end(), f.derived[0].values.begin(), f.derived[0].values.end());
  EXPECT_EQ(asFloats(std::get<std::vector<std::uint8_t>>(encode(f, ImageFileFormat::kRaw, planes))),
            expected);
  std::vector<std::string> names;
  const std::vector<float> exr =
      decoded<float>(encode(f, ImageFileFormat::kExr, planes), ".exr", 2, &names);
  ASSERT_EQ(exr.size(), 12u);
  for (int c = 0; c < 2; ++c) {
    const std::vector<float>& plane = names[c] == "lwir" ? f.lwir : f.derived[0].values;
    EXPECT_TRUE(names[c] == "lwir" || names[c] == "kelvin") << names[c];
    for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(exr[i * 2 + c], plane[i]) << names[c] << i;
  }
  EXPECT_NE(names[0], names[1]);
}

TEST(Encode, CroppingAFrameCropsItsDerivedPlanes) {
  const Frame crop = greyFrame().cropped(1, 1, 2, 1);
  ASSERT_EQ(crop.derived.size(), 2u);
  EXPECT_EQ(crop.derivedPlane("kelvin")->values, (std::vector<float>{319.9f, 340.0f}));
}

// A video stream takes the same 8-bit pixels as encode: the frame's own, shared, or its
// colour sRGB-encoded.
TEST(Encode, Srgb8PixelsAreTheFramesOwnOrItsColourEncoded) {
  auto own = std::make_shared<Frame>(smallFrame());
  own->srgb = {2, 1, true, {1, 2, 3, 4, 5, 6, 7, 8}};
  EXPECT_EQ(srgb8Pixels(std::shared_ptr<const Frame>(own)).get(), &own->srgb);
  const auto converted = srgb8Pixels(std::make_shared<const Frame>(smallFrame()));
  const std::vector<float>& linear = smallFrame().colour.rgba;
  ASSERT_EQ(converted->rgba.size(), linear.size());
  for (std::size_t i = 0; i < linear.size(); ++i)
    EXPECT_EQ(converted->rgba[i], toByte(i % 4 == 3 ? linear[i] : srgbEncode(linear[i]))) << i;
}

}  // namespace
}  // namespace nephele
