#pragma once
// Rendered images to files through OpenImageIO, the format chosen by the file extension:
// PNG, JPEG and TIFF as 8-bit sRGB RGB, EXR as linear float RGB plus coverage alpha.
#include <bit>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "image/image.h"

namespace nephele {

// kRaw: pixels alone, no container (the socket protocol's raw images); never a file's.
enum class ImageFileFormat { kRaw, kPng, kJpeg, kTiff, kExr };

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

// One 16-bit grey PNG in memory (instance masks: the value is an id), rows top-down.
std::string encodeMaskPng(int width, int height, const std::vector<std::uint16_t>& values,
                          const EncodeOptions& options, std::vector<std::uint8_t>& out);

// Named float planes as one EXR: `stride` floats between a plane's pixels, rows top-down.
// Colour-like planes (R, G, B, A) follow options.exr_half; every other plane is 32-bit float,
// since half floats cannot hold distances (65504 at most, 4 m steps at 5 km). `attributes`
// become EXR header attributes (float when numeric).
struct ExrPlane {
  std::string name;
  const float* data;
  std::ptrdiff_t stride = 1;
};
struct ImageAttribute {
  std::string name;
  double number = 0.0;
  std::string text;  // used when not empty
};
std::string writeExrPlanes(const std::string& path, int width, int height,
                           const std::vector<ExrPlane>& planes,
                           const std::vector<ImageAttribute>& attributes,
                           const EncodeOptions& options = {});
std::string encodeExrPlanes(int width, int height, const std::vector<ExrPlane>& planes,
                            const std::vector<ImageAttribute>& attributes,
                            const EncodeOptions& options, std::vector<std::uint8_t>& out);

// An 8-bit image in memory (renderer/encode.h's encode for every format and channel).
// `colour` selects RGB and `coverage` the alpha; returns an empty string on success, else what
// went wrong. PNG and TIFF take any selection, JPEG colour only; EXR is float
// (encodeExrPlanes).
std::string encodeImage(ImageFileFormat format, const Srgb8Image& image, bool colour, bool coverage,
                        const EncodeOptions& options, std::vector<std::uint8_t>& out);
// Raw 8-bit pixels, rows top-down, the selected channels packed per pixel.
std::vector<std::uint8_t> packRaw(const Srgb8Image& image, bool colour, bool coverage);

// sRGB-encodes a linear float image to bytes (top-down), keeping alpha linear.
Srgb8Image toSrgb8(const FloatImage& image);

// The IEEE 754 binary16 bits of f, rounded to the nearest half (ties to even): beyond the
// largest half an infinity, a NaN stays a NaN, below 2^-14 a subnormal. For tables handed to
// GL as half floats, which llvmpipe would otherwise convert a texel at a time.
inline std::uint16_t halfFloatBits(float f) {
  // Each case computed and the right one selected, without branches, so that loops over
  // tables of them run in SIMD lanes. Magnitudes as signed ints, which SSE2 compares.
  const std::uint32_t x = std::bit_cast<std::uint32_t>(f);
  const std::uint32_t sign = (x >> 16) & 0x8000u;
  const std::int32_t a = std::int32_t(x & 0x7fffffffu);
  // Normal: exponent bias 127 -> 15, the 13 dropped bits rounded to even (a carry may reach
  // the exponent, and from 65520 on gives the infinity).
  const std::uint32_t normal = (std::uint32_t(a) - 0x38000000u + 0x0fffu + ((a >> 13) & 1)) >> 13;
  // Below 2^-14, subnormal: in 0.5 + |f| the float's last mantissa bit weighs 2^-24, the
  // half's subnormal step, so the FPU's own rounding gives the half's mantissa.
  const std::uint32_t subnormal =
      std::bit_cast<std::uint32_t>(std::bit_cast<float>(a) + 0.5f) - 0x3f000000u;
  // From 2^16 on, infinity, and a NaN stays a NaN.
  const std::uint32_t beyond = 0x7c00u | (std::uint32_t(a > 0x7f800000) << 9);
  const std::uint32_t is_beyond = 0u - std::uint32_t(a >= 0x47800000);  // all ones or zero
  const std::uint32_t is_subnormal = 0u - std::uint32_t(a < 0x38800000);
  const std::uint32_t h =
      (is_beyond & beyond) | (~is_beyond & ((is_subnormal & subnormal) | (~is_subnormal & normal)));
  return std::uint16_t(sign | h);
}

}  // namespace nephele
