#pragma once
// Image buffers handed from renderers to encoders. Rows run top to bottom unless stated.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace nephele {

// Linear RGB plus coverage alpha, 4 floats per pixel.
struct FloatImage {
  int width = 0;
  int height = 0;
  std::vector<float> rgba;

  float* pixel(int x, int y) { return &rgba[(std::size_t(y) * width + x) * 4]; }
  const float* pixel(int x, int y) const { return &rgba[(std::size_t(y) * width + x) * 4]; }
};

// sRGB-encoded RGB plus linear coverage alpha, 4 bytes per pixel.
struct Srgb8Image {
  int width = 0;
  int height = 0;
  bool bottom_up = false;  // rows stored bottom row first (GL readback order)
  std::vector<std::uint8_t> rgba;
};

// The w x h rectangle at (x0, y0), counted from the top-left corner, of a plane of `channels`
// values per pixel stored top row first (or bottom row first).
template <class T>
std::vector<T> cropPlane(const std::vector<T>& plane, int width, int height, int channels, int x0,
                         int y0, int w, int h, bool bottom_up = false) {
  std::vector<T> out(std::size_t(w) * h * channels);
  for (int y = 0; y < h; ++y) {
    const int src_row = bottom_up ? height - 1 - (y0 + y) : y0 + y;
    const int dst_row = bottom_up ? h - 1 - y : y;
    std::copy_n(plane.begin() + (std::ptrdiff_t(src_row) * width + x0) * channels,
                std::size_t(w) * channels, out.begin() + std::ptrdiff_t(dst_row) * w * channels);
  }
  return out;
}

inline FloatImage cropImage(const FloatImage& image, int x0, int y0, int w, int h) {
  return {w, h, cropPlane(image.rgba, image.width, image.height, 4, x0, y0, w, h)};
}

inline Srgb8Image cropImage(const Srgb8Image& image, int x0, int y0, int w, int h) {
  return {w, h, image.bottom_up,
          cropPlane(image.rgba, image.width, image.height, 4, x0, y0, w, h, image.bottom_up)};
}

// sRGB transfer function (IEC 61966-2-1), linear [0, 1] to encoded [0, 1].
inline double srgbEncode(double linear) {
  if (!(linear > 0.0)) return 0.0;
  if (linear >= 1.0) return 1.0;
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

inline std::uint8_t toByte(double unit) {
  return std::uint8_t(std::lround((unit > 0.0 ? (unit < 1.0 ? unit : 1.0) : 0.0) * 255.0));
}

}  // namespace nephele
