#pragma once
// How a frame becomes bytes: one encoder for every format, used by the daemon's replies,
// subscriptions and files, the render command's file and the dataset's images.
#include <cstdint>
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
// 8-bit pixels come from frame.srgb, or sRGB-encoded from frame.colour when it has none.
// Every EXR is made by writeExrPlanes' encoder, with the frame's pose and clock as
// attributes for float planes (docs/DATASETS.md).
Encoded encode(const Frame& frame, ImageFileFormat format, const Channels& channels,
               const EncodeOptions& options = {});
// The same as a file, in the format of its extension; written beside its final name and
// renamed. Empty on success, else what went wrong.
std::string writeImage(const std::string& path, const Frame& frame, const Channels& channels,
                       const EncodeOptions& options = {});

// The frame's pose, intrinsics and clock as image attributes (docs/DATASETS.md).
std::vector<ImageAttribute> frameAttributes(const FrameInfo& info);
// The EXR layers of the channels in `order` (colour as R, G, B, coverage as A).
std::vector<ExrPlane> exrPlanesOf(const Frame& frame, const std::vector<Channel>& order);

}  // namespace nephele
