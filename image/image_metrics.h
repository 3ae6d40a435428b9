#pragma once
// Error between two renders of the same view, measured as a viewer sees it: on sRGB-encoded
// RGB in [0, 1] (coverage is compared separately, linearly).
#include "image/image.h"

namespace nephele {

struct ImageError {
  double psnr_db = 0.0;        // 10 log10(1 / MSE) over sRGB RGB; +inf when identical
  double max_abs = 0.0;        // largest sRGB channel difference, in [0, 1]
  double rms = 0.0;            // root mean square sRGB difference
  double coverage_max = 0.0;   // largest coverage (alpha) difference
  double coverage_rms = 0.0;   // root mean square coverage difference
  double coverage_psnr = 0.0;  // 10 log10(1 / coverage MSE); +inf when identical
  int non_finite = 0;          // pixels with a NaN or Inf in either image
};

ImageError compareImages(const FloatImage& actual, const FloatImage& expected);

// An impostor cannot match what it stands for pixel by pixel, only its amount and brightness
// at each distance: the largest difference, over bands of `band` image rows (on level ground
// a row is a line of equal distance), of the mean coverage and of the mean linear luminance
// (the mean of R, G and B).
struct ProfileError {
  double cover = 0.0, luminance = 0.0;
};
ProfileError rowProfileError(const FloatImage& actual, const FloatImage& expected, int band = 8);

// |actual - expected| per channel, scaled by `gain`, as a float image for inspection.
// A label plane (one float per pixel; +inf meaning none, as cloud depth) against an exact
// one: the fraction of pixels whose value turns finite or infinite, and the mean relative
// and absolute differences where both are finite.
struct PlaneError {
  double flipped = 0.0;
  double mean_relative = 0.0;
  double mean_abs = 0.0;
};
PlaneError comparePlanes(const std::vector<float>& actual, const std::vector<float>& expected);

FloatImage differenceImage(const FloatImage& actual, const FloatImage& expected, float gain);

}  // namespace nephele
