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

// A float plane `channels` names that the frame lacks, or empty. 8-bit colour may come from
// the frame's 8-bit pixels instead (srgb8Pixels).
std::string missingPlane(const Frame& frame, const Channels& channels) {
  if (channels.pixels != Channels::Pixels::kSrgb8)
    for (Channel c : channels.order) {
      const std::vector<float>* own = frame.ownPlane(c);
      if (own ? own->empty() : frame.colour.rgba.empty())
        return std::string("the frame has no ") + channelName(c) + " plane";
    }
  for (const std::string& name : channels.derived)
    if (!frame.derivedPlane(name)) return "the frame has no derived plane '" + name + "'";
  return "";
}

// Float32 planes, one per named plane (colour as three), rows top-down.
std::vector<std::uint8_t> floatPlanes(const Frame& f, const Channels& channels) {
  const std::size_t pixels = std::size_t(f.width()) * f.height();
  const std::vector<ExrPlane> named = namedPlanes(f, channels);
  std::vector<float> planes;
  planes.reserve(pixels * named.size());
  for (const ExrPlane& p : named)
    for (std::size_t i = 0; i < pixels; ++i) planes.push_back(p.data[std::ptrdiff_t(i) * p.stride]);
  const auto* raw = reinterpret_cast<const std::uint8_t*>(planes.data());
  return std::vector<std::uint8_t>(raw, raw + planes.size() * sizeof(float));
}

Encoded encodeSrgb8(const Frame& frame, ImageFileFormat format, const Channels& channels,
                    const EncodeOptions& options) {
  const bool colour = channels.has(Channel::kColour);
  const bool coverage = channels.has(Channel::kCoverage);
  Srgb8Image converted;
  const Srgb8Image& image = srgb8Pixels(frame, converted);
  if (format == ImageFileFormat::kRaw) return packRaw(image, colour, coverage);
  std::vector<std::uint8_t> bytes;
  const std::string error = encodeImage(format, image, colour, coverage, options, bytes);
  return bytesOrError(error, bytes);
}

// Linear colour and coverage, or float planes with the frame's attributes.
Encoded encodeExr(const Frame& frame, const Channels& channels, const EncodeOptions& options) {
  const bool planes = channels.pixels == Channels::Pixels::kPlanes;
  Channels asked = channels;
  if (!planes) {  // R, G, B then A, whatever the order asked
    asked = Channels{{}, channels.pixels};
    if (channels.has(Channel::kColour)) asked.order.push_back(Channel::kColour);
    if (channels.has(Channel::kCoverage)) asked.order.push_back(Channel::kCoverage);
  }
  std::vector<std::uint8_t> bytes;
  const std::string error = encodeExrPlanes(
      frame.colour.rgba.empty() ? frame.width() : frame.colour.width,
      frame.colour.rgba.empty() ? frame.height() : frame.colour.height, namedPlanes(frame, asked),
      planes ? frameAttributes(frame.info) : std::vector<ImageAttribute>{}, options, bytes);
  return bytesOrError(error, bytes);
}

// One plane as 16-bit grey: each value rounded to the nearest integer in 0..65535.
Encoded encodeGrey16(const Frame& frame, ImageFileFormat format, const ExrPlane& plane,
                     const EncodeOptions& options) {
  if (format != ImageFileFormat::kPng) return std::string("16-bit grey is PNG only");
  std::vector<std::uint16_t> values(std::size_t(frame.width()) * frame.height());
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i] = std::uint16_t(
        std::clamp(std::lround(plane.data[std::ptrdiff_t(i) * plane.stride]), 0L, 65535L));
  std::vector<std::uint8_t> bytes;
  const std::string error = encodeMaskPng(frame.width(), frame.height(), values, options, bytes);
  return bytesOrError(error, bytes);
}

// One plane as 8-bit grey (Channels::Pixels::kGrey8) or 16-bit (kGrey16).
Encoded encodeGrey(const Frame& frame, ImageFileFormat format, const Channels& channels,
                   const EncodeOptions& options) {
  const std::vector<ExrPlane> planes = namedPlanes(frame, channels);
  if (planes.size() != 1) return std::string("grey pixels are one plane");
  const ExrPlane& plane = planes.front();
  if (channels.pixels == Channels::Pixels::kGrey16)
    return encodeGrey16(frame, format, plane, options);
  const std::size_t pixels = std::size_t(frame.width()) * frame.height();
  Srgb8Image grey{frame.width(), frame.height(), false, std::vector<std::uint8_t>(pixels * 4, 255)};
  const double range = channels.grey_hi - channels.grey_lo;
  for (std::size_t i = 0; i < pixels; ++i) {
    const float v = plane.data[std::ptrdiff_t(i) * plane.stride];
    grey.rgba[i * 4] = grey.rgba[i * 4 + 1] = grey.rgba[i * 4 + 2] =
        toByte((v - channels.grey_lo) / range);
  }
  if (format == ImageFileFormat::kRaw) return packRaw(grey, true, false);
  std::vector<std::uint8_t> bytes;
  const std::string error = encodeImage(format, grey, true, false, options, bytes);
  return bytesOrError(error, bytes);
}

}  // namespace

Encoded encode(const Frame& frame, ImageFileFormat format, const Channels& channels,
               const EncodeOptions& options) {
  using Pixels = Channels::Pixels;
  if (std::string missing = missingPlane(frame, channels); !missing.empty()) return missing;
  if (format == ImageFileFormat::kExr) {
    if (channels.pixels != Pixels::kLinear && channels.pixels != Pixels::kPlanes)
      return std::string("EXR needs a float image");
    return encodeExr(frame, channels, options);
  }
  switch (channels.pixels) {
    case Pixels::kSrgb8:
      return encodeSrgb8(frame, format, channels, options);
    case Pixels::kLinear:
      return std::string("linear pixels are EXR only");
    case Pixels::kPlanes:
      if (format == ImageFileFormat::kRaw) return floatPlanes(frame, channels);
      return std::string("float planes are raw or EXR only");
    case Pixels::kGrey8:
    case Pixels::kGrey16:
      return encodeGrey(frame, format, channels, options);
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

const Srgb8Image& srgb8Pixels(const Frame& frame, Srgb8Image& converted) {
  if (!frame.srgb.rgba.empty()) return frame.srgb;
  converted = toSrgb8(frame.colour);
  return converted;
}

std::shared_ptr<const Srgb8Image> srgb8Pixels(std::shared_ptr<const Frame> frame) {
  if (!frame->srgb.rgba.empty()) return {frame, &frame->srgb};  // shares the frame's ownership
  return std::make_shared<const Srgb8Image>(toSrgb8(frame->colour));
}

std::vector<ExrPlane> namedPlanes(const Frame& frame, const Channels& channels) {
  std::vector<ExrPlane> planes;
  const float* rgba = frame.colour.rgba.data();
  for (Channel c : channels.order) {
    if (c == Channel::kColour)
      for (int k = 0; k < 3; ++k) planes.push_back({std::string(1, "RGB"[k]), rgba + k, 4});
    else if (c == Channel::kCoverage)
      planes.push_back({"A", rgba + 3, 4});
    else
      planes.push_back({channelName(c), frame.ownPlane(c)->data(), 1});
  }
  for (const std::string& name : channels.derived)
    if (const DerivedPlane* d = frame.derivedPlane(name))
      planes.push_back({d->name, d->values.data(), 1});
  return planes;
}

}  // namespace nephele
