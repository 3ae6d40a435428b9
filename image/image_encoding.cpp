#include "image/image_encoding.h"

#include "world/file_output.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace nephele {
namespace {

namespace oiio = OIIO;

std::string lowerExtension(std::string_view path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// Writes one image into `out` through an in-memory proxy.
std::string encodeWithOiio(const char* extension, const oiio::ImageSpec& spec,
                           oiio::TypeDesc pixel_type, const void* first_row,
                           std::ptrdiff_t x_stride, std::ptrdiff_t y_stride,
                           std::vector<std::uint8_t>& out) {
  out.clear();
  oiio::Filesystem::IOVecOutput proxy(out);
  const std::string name = std::string("frame") + extension;
  auto writer = oiio::ImageOutput::create(name);
  if (!writer) return "no encoder for " + name + ": " + oiio::geterror();
  oiio::ImageSpec file_spec = spec;
  // OpenImageIO 2.4's TIFF writer cannot put its Exif directory through an I/O proxy (the
  // file comes out truncated); the image needs none.
  file_spec.attribute("tiff:write_exif", 0);
  if (!writer->set_ioproxy(&proxy) || !writer->open(name, file_spec))
    return "cannot encode " + name + ": " + writer->geterror();
  const bool written = writer->write_image(pixel_type, first_row, x_stride, y_stride);
  const std::string write_error = written ? "" : writer->geterror();
  // Some writers report a failure only through their error text.
  if (!writer->close() || !written || writer->has_error())
    return "encoding " + name + " failed: " + (written ? writer->geterror() : write_error);
  return "";
}

// Encodes in memory and writes the file through writeFileAtomically: the codec never touches
// the disk, so no codec's I/O error handling can end the process or leave a partial file.
std::string writeWithOiio(const std::string& path, ImageFileFormat format,
                          const oiio::ImageSpec& spec, oiio::TypeDesc pixel_type,
                          const void* first_row, std::ptrdiff_t x_stride, std::ptrdiff_t y_stride) {
  const char* extension = format == ImageFileFormat::kPng    ? ".png"
                          : format == ImageFileFormat::kJpeg ? ".jpg"
                          : format == ImageFileFormat::kTiff ? ".tif"
                                                             : ".exr";
  std::vector<std::uint8_t> bytes;
  if (std::string e =
          encodeWithOiio(extension, spec, pixel_type, first_row, x_stride, y_stride, bytes);
      !e.empty())
    return "cannot write '" + path + "': " + e;
  return writeFileAtomically(path, bytes, "image");
}

std::vector<std::string> channelNamesFor(bool colour, bool coverage) {
  std::vector<std::string> names;
  if (colour) names = {"R", "G", "B"};
  if (coverage) names.push_back("A");
  return names;
}

// libpng's row filters (png.h): one fixed filter, where libpng's default tries every filter
// on every row. Over 48 dataset samples (docs/ACCURACY.md, "Dataset throughput"): images with
// "sub" 3,788 KB against 4,168 with the default and 4,264 with "none", in half the time; masks
// (mostly zeros) 196 KB with "none" or the default, 296 with "sub".
constexpr int kPngFilterNone = 0x08;
constexpr int kPngFilterSub = 0x10;

void setPngOptions(oiio::ImageSpec& spec, const EncodeOptions& options, int filter) {
  spec.attribute("png:compressionLevel", std::clamp(options.png_compression, 0, 9));
  spec.attribute("png:filter", filter);
}

std::string unknownExtension(const std::string& path) {
  return "unknown image extension in '" + path + "' (allowed: " + std::string(kImageExtensions) +
         ")";
}

}  // namespace

std::optional<ImageFileFormat> imageFileFormatForPath(std::string_view path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".png") return ImageFileFormat::kPng;
  if (ext == ".jpg" || ext == ".jpeg") return ImageFileFormat::kJpeg;
  if (ext == ".tif" || ext == ".tiff") return ImageFileFormat::kTiff;
  if (ext == ".exr") return ImageFileFormat::kExr;
  return std::nullopt;
}

Srgb8Image toSrgb8(const FloatImage& image) {
  // The byte of each linear value from the 255 thresholds between bytes, the same rounding as
  // toByte(srgbEncode(v)). A value's top 16 bits (sign, exponent, 7 bits of mantissa) pick a
  // bucket no more than 1/128 of the value wide, which no two thresholds share (they lie at
  // least 0.89 % apart, near 1), so the byte is the bucket's first byte or the one after it.
  struct Table {
    std::array<float, 255> thresholds{};
    std::array<std::uint8_t, 65536> first{};
  };
  static const Table table = [] {
    Table t;
    for (int b = 0; b < 255; ++b) {
      // Smallest linear value encoding to byte b + 1 (bisection on the monotone encoder).
      double lo = 0.0, hi = 1.0;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (toByte(srgbEncode(mid)) > b ? hi : lo) = mid;
      }
      // The least float at or above it, so that v >= threshold holds for exactly the floats
      // the formula takes to b + 1.
      float up = float(hi);
      if (double(up) < hi) up = std::nextafter(up, 2.0f);
      t.thresholds[b] = up;
    }
    for (std::uint32_t bucket = 0; bucket < 65536; ++bucket) {
      const float v = std::bit_cast<float>(bucket << 16);  // the bucket's least value
      t.first[bucket] = std::uint8_t(
          v >= t.thresholds[0]
              ? std::upper_bound(t.thresholds.begin(), t.thresholds.end(), v) - t.thresholds.begin()
              : 0);
    }
    return t;
  }();
  Srgb8Image out{image.width, image.height, false, std::vector<std::uint8_t>(image.rgba.size())};
  for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
    for (int c = 0; c < 3; ++c) {
      const float v = image.rgba[i + c];
      std::uint8_t byte = 0;
      if (v >= table.thresholds[0]) {  // false for NaN and what rounds to 0
        byte = table.first[std::bit_cast<std::uint32_t>(v) >> 16];
        if (byte < 255 && v >= table.thresholds[byte]) ++byte;
      }
      out.rgba[i + c] = byte;
    }
    out.rgba[i + 3] = toByte(image.rgba[i + 3]);
  }
  return out;
}

std::string writeImageFile(const std::string& path, const Srgb8Image& image,
                           const EncodeOptions& options) {
  const auto format = imageFileFormatForPath(path);
  if (!format) return unknownExtension(path);
  if (isFloatFormat(*format)) return "'" + path + "' is a float format; it needs a float image";
  // 8-bit files are for viewing: RGB only (coverage goes to EXR, where it is the alpha).
  oiio::ImageSpec spec(image.width, image.height, 3, oiio::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  if (*format == ImageFileFormat::kPng) setPngOptions(spec, options, kPngFilterSub);
  if (*format == ImageFileFormat::kJpeg)
    spec.attribute("Compression",
                   "jpeg:" + std::to_string(std::clamp(options.jpeg_quality, 1, 100)));
  const std::ptrdiff_t row = std::ptrdiff_t(image.width) * 4;
  // GL readback is bottom-up: write it with a negative row stride instead of copying.
  const std::uint8_t* first =
      image.bottom_up ? image.rgba.data() + row * (image.height - 1) : image.rgba.data();
  return writeWithOiio(path, *format, spec, oiio::TypeDesc::UINT8, first, 4,
                       image.bottom_up ? -row : row);
}

std::string writeImageFile(const std::string& path, const FloatImage& image,
                           const EncodeOptions& options) {
  const auto format = imageFileFormatForPath(path);
  if (!format) return unknownExtension(path);
  if (!isFloatFormat(*format)) return writeImageFile(path, toSrgb8(image), options);
  const float* rgba = image.rgba.data();
  return writeExrPlanes(
      path, image.width, image.height,
      {{"R", rgba, 4}, {"G", rgba + 1, 4}, {"B", rgba + 2, 4}, {"A", rgba + 3, 4}}, {}, options);
}

std::string encodeImage(ImageFileFormat format, const Srgb8Image& image, bool colour, bool coverage,
                        const EncodeOptions& options, std::vector<std::uint8_t>& out) {
  if (!colour && !coverage) return "no channels selected";
  if (format == ImageFileFormat::kExr) return "EXR needs a float image";
  if (format == ImageFileFormat::kJpeg && (coverage || !colour)) return "JPEG holds colour only";
  const int channels = (colour ? 3 : 0) + (coverage ? 1 : 0);
  oiio::ImageSpec spec(image.width, image.height, channels, oiio::TypeDesc::UINT8);
  spec.channelnames = channelNamesFor(colour, coverage);
  spec.alpha_channel = coverage ? channels - 1 : -1;
  // Colour is the whole composited image (sky included), not premultiplied by coverage:
  // write it as it is.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  spec.attribute("oiio:ColorSpace", "sRGB");
  if (format == ImageFileFormat::kPng) setPngOptions(spec, options, kPngFilterSub);
  if (format == ImageFileFormat::kJpeg)
    spec.attribute("Compression",
                   "jpeg:" + std::to_string(std::clamp(options.jpeg_quality, 1, 100)));
  const std::ptrdiff_t row = std::ptrdiff_t(image.width) * 4;
  const std::uint8_t* first =
      (image.bottom_up ? image.rgba.data() + row * (image.height - 1) : image.rgba.data()) +
      (colour ? 0 : 3);
  const char* extension = format == ImageFileFormat::kPng    ? ".png"
                          : format == ImageFileFormat::kJpeg ? ".jpg"
                                                             : ".tif";
  return encodeWithOiio(extension, spec, oiio::TypeDesc::UINT8, first, 4,
                        image.bottom_up ? -row : row, out);
}

std::vector<std::uint8_t> packRaw(const Srgb8Image& image, bool colour, bool coverage) {
  const int channels = (colour ? 3 : 0) + (coverage ? 1 : 0);
  std::vector<std::uint8_t> out(std::size_t(image.width) * image.height * channels);
  std::uint8_t* dst = out.data();
  for (int y = 0; y < image.height; ++y) {
    const int source_row = image.bottom_up ? image.height - 1 - y : y;
    const std::uint8_t* src = image.rgba.data() + std::size_t(source_row) * image.width * 4;
    if (channels == 4) {
      std::memcpy(dst, src, std::size_t(image.width) * 4);
      dst += std::size_t(image.width) * 4;
      continue;
    }
    for (int x = 0; x < image.width; ++x, src += 4) {
      if (colour) dst = std::copy(src, src + 3, dst);
      if (coverage) *dst++ = src[3];
    }
  }
  return out;
}

oiio::ImageSpec maskSpec(int width, int height, const EncodeOptions& options) {
  oiio::ImageSpec spec(width, height, 1, oiio::TypeDesc::UINT16);
  setPngOptions(spec, options, kPngFilterNone);
  return spec;
}

std::string encodeMaskPng(int width, int height, const std::vector<std::uint16_t>& values,
                          const EncodeOptions& options, std::vector<std::uint8_t>& out) {
  return encodeWithOiio(".png", maskSpec(width, height, options), oiio::TypeDesc::UINT16,
                        values.data(), sizeof(std::uint16_t),
                        std::ptrdiff_t(width) * sizeof(std::uint16_t), out);
}

namespace {

// The spec and interleaved pixels of named planes (writeExrPlanes, encodeExrPlanes).
std::string exrPlanes(int width, int height, const std::vector<ExrPlane>& planes,
                      const std::vector<ImageAttribute>& attributes, const EncodeOptions& options,
                      oiio::ImageSpec& spec, std::vector<float>& pixels) {
  const int n = int(planes.size());
  if (n == 0) return "no channel to write";
  spec = oiio::ImageSpec(width, height, n, oiio::TypeDesc::FLOAT);
  spec.channelnames.clear();
  for (int c = 0; c < n; ++c) {
    const std::string& name = planes[c].name;
    const bool colour = name == "R" || name == "G" || name == "B" || name == "A";
    spec.channelnames.push_back(name);
    spec.channelformats.push_back(colour && options.exr_half ? oiio::TypeDesc::HALF
                                                             : oiio::TypeDesc::FLOAT);
    if (name == "A") spec.alpha_channel = c;
  }
  spec.attribute("compression", options.exr_compression);
  spec.attribute("oiio:ColorSpace", "Linear");
  for (const ImageAttribute& a : attributes) {
    if (a.text.empty())
      spec.attribute(a.name, float(a.number));
    else
      spec.attribute(a.name, a.text);
  }
  pixels.assign(std::size_t(width) * height * n, 0.0f);
  for (std::size_t i = 0; i < std::size_t(width) * height; ++i)
    for (int c = 0; c < n; ++c) pixels[i * n + c] = planes[c].data[i * planes[c].stride];
  return "";
}

}  // namespace

std::string writeExrPlanes(const std::string& path, int width, int height,
                           const std::vector<ExrPlane>& planes,
                           const std::vector<ImageAttribute>& attributes,
                           const EncodeOptions& options) {
  oiio::ImageSpec spec;
  std::vector<float> pixels;
  if (std::string e = exrPlanes(width, height, planes, attributes, options, spec, pixels);
      !e.empty())
    return "cannot write '" + path + "': " + e;
  const std::ptrdiff_t n = std::ptrdiff_t(planes.size());
  return writeWithOiio(path, ImageFileFormat::kExr, spec, oiio::TypeDesc::FLOAT, pixels.data(),
                       n * sizeof(float), std::ptrdiff_t(width) * n * sizeof(float));
}

std::string encodeExrPlanes(int width, int height, const std::vector<ExrPlane>& planes,
                            const std::vector<ImageAttribute>& attributes,
                            const EncodeOptions& options, std::vector<std::uint8_t>& out) {
  oiio::ImageSpec spec;
  std::vector<float> pixels;
  if (std::string e = exrPlanes(width, height, planes, attributes, options, spec, pixels);
      !e.empty())
    return e;
  const std::ptrdiff_t n = std::ptrdiff_t(planes.size());
  return encodeWithOiio(".exr", spec, oiio::TypeDesc::FLOAT, pixels.data(), n * sizeof(float),
                        std::ptrdiff_t(width) * n * sizeof(float), out);
}

}  // namespace nephele
