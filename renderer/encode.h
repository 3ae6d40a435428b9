#pragma once
// How a frame becomes bytes: one encoder for every format, used by the daemon's replies,
// subscriptions and files, the render command's file and the dataset's images.
#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "image/image_encoding.h"
#include "renderer/frame.h"

namespace nephele {

// Encoded bytes, or what went wrong.
using Encoded = std::variant<std::vector<std::uint8_t>, std::string>;

// `frame`'s `channels` as `format`, rows top-down. Raw is the pixels alone: 8-bit ones packed
// per pixel, float planes as float32 in host byte order (little-endian on x86-64 and ARM).
// 8-bit colour comes from srgb8Pixels, every float plane from namedPlanes. Every EXR is made
// by writeExrPlanes' encoder, with the frame's pose and clock as attributes for float planes
// (docs/DATASETS.md). Grey pixels: 8-bit as PNG, JPEG, TIFF or raw, 16-bit as PNG.
Encoded encode(const Frame& frame, ImageFileFormat format, const Channels& channels,
               const EncodeOptions& options = {});
// The same as a file, in the format of its extension; written beside its final name and
// renamed. Empty on success, else what went wrong.
std::string writeImage(const std::string& path, const Frame& frame, const Channels& channels,
                       const EncodeOptions& options = {});

// The frame's pose, intrinsics and clock as image attributes (docs/DATASETS.md).
std::vector<ImageAttribute> frameAttributes(const FrameInfo& info);
// The frame's 8-bit sRGB pixels, which encode's 8-bit formats and a video stream take: its
// own (the GL back end's 8-bit target), else sRGB-encoded from its linear colour (into
// `converted`, or a new image that the returned pointer owns).
const Srgb8Image& srgb8Pixels(const Frame& frame, Srgb8Image& converted);
std::shared_ptr<const Srgb8Image> srgb8Pixels(std::shared_ptr<const Frame> frame);
// The float planes of the channels in `channels.order` (colour as R, G, B, coverage as A),
// then of its derived planes, by name, pointing into the frame. A derived plane the frame
// lacks is left out (encode says so).
std::vector<ExrPlane> namedPlanes(const Frame& frame, const Channels& channels);

}  // namespace nephele
