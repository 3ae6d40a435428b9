#pragma once
// Rendered images to files through OpenImageIO, the format chosen by the file extension:
// PNG, JPEG and TIFF as 8-bit sRGB RGB, EXR as linear float RGB plus coverage alpha.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "image/image.h"

namespace nephele {

enum class ImageFileFormat { kPng, kJpeg, kTiff, kExr };

// The format for a path's extension (case-insensitive), or nothing for an unknown one.
std::optional<ImageFileFormat> imageFileFormatForPath(std::string_view path);
inline bool isFloatFormat(ImageFileFormat f) {
  return f == ImageFileFormat::kExr;
}
inline constexpr std::string_view kImageExtensions = ".png, .jpg, .jpeg, .tif, .tiff, .exr";

struct EncodeOptions {
  int png_compression = 6;              // zlib level 0..9; 1 is about 25 % faster at 1280x1024
  int jpeg_quality = 92;                // 1..100
  std::string exr_compression = "zip";  // none, zip, zips, piz, rle, pxr24, b44, dwaa, dwab
  bool exr_half = true;                 // 16-bit half floats; false writes 32-bit floats
};

// Both return an empty string on success, else what went wrong. The file appears only
// complete: it is written beside its final name and renamed.
std::string writeImageFile(const std::string& path, const FloatImage& image,
                           const EncodeOptions& options = {});
std::string writeImageFile(const std::string& path, const Srgb8Image& image,
                           const EncodeOptions& options = {});

// In-memory images for the socket protocol. `colour` selects RGB and `coverage` the alpha;
// each returns an empty string on success, else what went wrong. PNG takes any selection,
// JPEG colour only; EXR is linear float (half unless options say otherwise).
std::string encodeImage(ImageFileFormat format, const Srgb8Image& image, bool colour, bool coverage,
                        const EncodeOptions& options, std::vector<std::uint8_t>& out);
std::string encodeImage(const FloatImage& image, bool colour, bool coverage,
                        const EncodeOptions& options, std::vector<std::uint8_t>& out);
// Raw 8-bit pixels, rows top-down, the selected channels packed per pixel.
std::vector<std::uint8_t> packRaw(const Srgb8Image& image, bool colour, bool coverage);

// sRGB-encodes a linear float image to bytes (top-down), keeping alpha linear.
Srgb8Image toSrgb8(const FloatImage& image);

}  // namespace nephele
