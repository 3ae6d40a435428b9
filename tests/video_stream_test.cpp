// Streamed views' encoder (image/video_stream.h): the tick stamp reads back what was written,
// and a stream fed faster than it encodes drops frames at once and counts them instead of
// holding the caller. The stream's pictures and timing end to end are stream_test.py's and
// stream_bench's.
#include <gtest/gtest.h>

#include <vector>

#include "image/video_stream.h"

namespace nephele {
namespace {

TEST(VideoStream, TheTickStampReadsBack) {
  const int width = 640, height = 48;
  std::vector<std::uint8_t> luma(std::size_t(width) * height, 90);
  for (std::uint32_t tick : {0u, 1u, 0x80000001u, 123456789u, 0xFFFFFFFFu}) {
    stampTick(luma.data(), width, width, height, tick);
    EXPECT_EQ(readTickStamp(luma.data(), width, width, height), tick);
  }
  // Too narrow to hold 32 blocks: no stamp, and none read.
  EXPECT_FALSE(readTickStamp(luma.data(), width, 500, height));
}

TEST(VideoStream, AStreamFedFasterThanItEncodesDropsAndCounts) {
  VideoStreamSettings settings;
  settings.address = "udp://127.0.0.1:9";  // the discard port: nobody needs to listen
  settings.encoder = "libx264";
  auto opened = VideoStream::open(settings, 1280, 720);
  ASSERT_TRUE(std::holds_alternative<std::unique_ptr<VideoStream>>(opened))
      << std::get<std::string>(opened);
  auto& stream = *std::get<std::unique_ptr<VideoStream>>(opened);
  EXPECT_EQ(stream.encoderName(), "libx264");
  auto image = std::make_shared<Srgb8Image>();
  image->width = 1280;
  image->height = 720;
  image->rgba.assign(std::size_t(1280) * 720 * 4, 128);
  int taken = 0;
  for (int i = 0; i < 40; ++i) taken += stream.push(image, std::uint64_t(i)) ? 1 : 0;
  // The queue holds kStreamQueue; the encoder may have taken one or two more meanwhile.
  EXPECT_LE(taken, 8);
  EXPECT_EQ(stream.stats().dropped, std::uint64_t(40 - taken));
}

TEST(VideoStream, BadSettingsAreNamed) {
  VideoStreamSettings settings;
  settings.address = "http://127.0.0.1:9";
  EXPECT_NE(videoStreamSettingsError(settings).find("address"), std::string::npos);
  settings.address = "udp://127.0.0.1:9";
  settings.encoder = "mpeg2video";
  EXPECT_NE(videoStreamSettingsError(settings).find("encoder"), std::string::npos);
  EXPECT_TRUE(std::holds_alternative<std::string>(VideoStream::open(settings, 64, 64)));
}

}  // namespace
}  // namespace nephele
