#include "renderer/encode.h"

#include <algorithm>
#include <ctime>

#include "world/file_output.h"

namespace nephele {
namespace {

Encoded bytesOrError(const std::string& error, std::vector<std::uint8_t>& bytes) {
  if (!error.empty()) return error;
  return std::move(bytes);
}

// Float32 planes, one per channel in `order`, colour as three.
std::vector<std::uint8_t> floatPlanes(const Frame& f, const std::vector<Channel>& order) {
  const std::size_t pixels = std::size_t(f.width()) * f.height();
  std::vector<float> planes;
  planes.reserve(pixels * (order.size() + 2));
  for (Channel c : order) {
    if (c == Channel::kColour) {
      for (int k = 0; k < 3; ++k)
        for (std::size_t i = 0; i < pixels; ++i) planes.push_back(f.colour.rgba[i * 4 + k]);
    } else {
      const std::vector<float> plane = f.plane(c);
      planes.insert(planes.end(), plane.begin(), plane.end());
    }
  }
  const auto* raw = reinterpret_cast<const std::uint8_t*>(planes.data());
  return std::vector<std::uint8_t>(raw, raw + planes.size() * sizeof(float));
}

Encoded encodeSrgb8(const Frame& frame, ImageFileFormat format, const Channels& channels,
                    const EncodeOptions& options) {
  const bool colour = channels.has(Channel::kColour);
  const bool coverage = channels.has(Channel::kCoverage);
  Srgb8Image converted;
  if (frame.srgb.rgba.empty()) converted = toSrgb8(frame.colour);
  const Srgb8Image& image = frame.srgb.rgba.empty() ? converted : frame.srgb;
  if (format == ImageFileFormat::kRaw) return packRaw(image, colour, coverage);
  std::vector<std::uint8_t> bytes;
  const std::string error = encodeImage(format, image, colour, coverage, options, bytes);
  return bytesOrError(error, bytes);
}

// Linear colour and coverage, or float planes with the frame's attributes.
Encoded encodeExr(const Frame& frame, const Channels& channels, const EncodeOptions& options) {
  const bool planes = channels.pixels == Channels::Pixels::kPlanes;
  std::vector<Channel> order = channels.order;
  if (!planes) {  // R, G, B then A, whatever the order asked
    order.clear();
    if (channels.has(Channel::kColour)) order.push_back(Channel::kColour);
    if (channels.has(Channel::kCoverage)) order.push_back(Channel::kCoverage);
  }
  std::vector<std::uint8_t> bytes;
  const std::string error = encodeExrPlanes(
      frame.colour.rgba.empty() ? frame.width() : frame.colour.width,
      frame.colour.rgba.empty() ? frame.height() : frame.colour.height, exrPlanesOf(frame, order),
      planes ? frameAttributes(frame.info) : std::vector<ImageAttribute>{}, options, bytes);
  return bytesOrError(error, bytes);
}

}  // namespace

Encoded encode(const Frame& frame, ImageFileFormat format, const Channels& channels,
               const EncodeOptions& options) {
  using Pixels = Channels::Pixels;
  if (format == ImageFileFormat::kExr) {
    if (channels.pixels == Pixels::kSrgb8) return std::string("EXR needs a float image");
    return encodeExr(frame, channels, options);
  }
  switch (channels.pixels) {
    case Pixels::kSrgb8:
      return encodeSrgb8(frame, format, channels, options);
    case Pixels::kLinear:
      return std::string("linear pixels are EXR only");
    case Pixels::kPlanes:
      if (format == ImageFileFormat::kRaw) return floatPlanes(frame, channels.order);
      return std::string("float planes are raw or EXR only");
  }
  return std::string("unknown pixels");
}

std::string writeImage(const std::string& path, const Frame& frame, const Channels& channels,
                       const EncodeOptions& options) {
  const auto format = imageFileFormatForPath(path);
  if (!format)
    return "unknown image extension in '" + path + "' (allowed: " + std::string(kImageExtensions) +
           ")";
  Encoded encoded = encode(frame, *format, channels, options);
  if (const auto* error = std::get_if<std::string>(&encoded))
    return "cannot write '" + path + "': " + *error;
  return writeFileAtomically(path, std::get<std::vector<std::uint8_t>>(encoded), "image");
}

std::vector<ImageAttribute> frameAttributes(const FrameInfo& info) {
  // DateTime is the simulation clock counted from the Unix epoch, not the wall clock: a frame
  // rendered twice is the same file.
  const std::time_t seconds = std::time_t(std::clamp(info.time_s, 0.0, 1e11));
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y:%m:%d %H:%M:%S", &utc);
  return {
      {"DateTime", 0.0, date},
      {"nephele:position_x", info.position.x, ""},
      {"nephele:position_y", info.position.y, ""},
      {"nephele:position_z", info.position.z, ""},
      {"nephele:heading_deg", info.orientation.heading_deg, ""},
      {"nephele:pitch_deg", info.orientation.pitch_deg, ""},
      {"nephele:roll_deg", info.orientation.roll_deg, ""},
      {"nephele:vfov_deg", info.vfov_deg, ""},
      {"nephele:focal_px", info.focal_px, ""},
      {"nephele:cx", info.cx, ""},
      {"nephele:cy", info.cy, ""},
      {"nephele:time_s", info.time_s, ""},
      {"nephele:tick", 0.0, std::to_string(info.tick)},
  };
}

std::vector<ExrPlane> exrPlanesOf(const Frame& frame, const std::vector<Channel>& order) {
  std::vector<ExrPlane> planes;
  const float* rgba = frame.colour.rgba.data();
  for (Channel c : order) {
    if (c == Channel::kColour)
      for (int k = 0; k < 3; ++k) planes.push_back({std::string(1, "RGB"[k]), rgba + k, 4});
    else if (c == Channel::kCoverage)
      planes.push_back({"A", rgba + 3, 4});
    else
      planes.push_back({channelName(c), frame.ownPlane(c)->data(), 1});
  }
  return planes;
}

}  // namespace nephele
