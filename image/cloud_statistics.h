#pragma once
// Statistics of rendered cloud fields, for the benchmarks and tests that compare them with
// observed clouds (docs/ACCURACY.md, "Realism"): cloud outlines on the coverage channel,
// their perimeter-area dimension and size distribution, and the spectrum of the radiance.
#include <complex>
#include <vector>

#include "image/image.h"

namespace nephele {

// In-place radix-2 FFT (size a power of two); the inverse divides by the size.
void fft(std::vector<std::complex<double>>& a, bool inverse);
// 2D transform of an n x n grid stored row by row (rows, then columns).
void fft2(std::vector<std::complex<double>>& g, int n, bool inverse);

// One cloud: a 4-connected region of pixels whose coverage exceeds one half.
struct CloudRegion {
  std::vector<int> pixels;  // indices y * width + x
  int perimeter = 0;        // pixel edges between the region and what is not cloud
};

// The clouds of an image that do not touch its border (a cloud cut by the frame has no whole
// outline) and hold at least `min_pixels` pixels.
std::vector<CloudRegion> cloudRegions(const FloatImage& image, int min_pixels);

// Slope and intercept of the least-squares line y = slope x + intercept.
struct LineFit {
  double slope = 0.0, intercept = 0.0;
  int points = 0;
};
LineFit fitLine(const std::vector<double>& x, const std::vector<double>& y);

// A fitted figure and the number of points (clouds or bins) it rests on.
struct Fitted {
  double value = 0.0;
  int points = 0;
};

// Perimeter-area dimension D (Lovejoy 1982): perimeter ~ area^(D / 2) over the clouds of at
// least `min_pixels`, fitted on log perimeter against log area. A raster outline counts pixel
// edges, which makes D = 1 for squares and biases it upwards for clouds a few pixels across.
Fitted perimeterAreaDimension(const std::vector<CloudRegion>& clouds, int min_pixels);

// The outline of one silhouette, given as its pixels in a w x h image (docs/ACCURACY.md,
// "Outline figures"):
// - dimension: the outline's divider dimension, D = 1 - d log P / d log s, where P(s) is the
//   perimeter (pixel edges times s) of the silhouette coarse-grained into s x s blocks (a block
//   is in it when at least half its pixels are), for s = 1, 2, 4, 8: a smooth outline keeps its
//   perimeter at every scale (D = 1 for an ellipse), a fractal one loses the detail each coarser
//   scale cannot hold (D = 1.26 for Koch's curve; cumulus outlines about 1.3 to 1.4).
// - near_ellipse: the fraction of its outline pixels (those with a 4-neighbour outside it)
//   within one pixel of the ellipse of the same second moments, measured along the ray from the
//   ellipse's centre: 1 for an ellipse, low for an outline of turrets and notches.
struct OutlineFigures {
  double dimension = 0.0, near_ellipse = 0.0;
};
OutlineFigures outlineFigures(const std::vector<int>& pixels, int width, int height);

// Exponent a of the cloud size distribution n(A) ~ A^-a (clouds per unit of area), fitted on
// logarithmic bins of area (four per decade) from `min_pixels` up, bins with clouds only.
Fitted sizeDistributionExponent(const std::vector<CloudRegion>& clouds, int min_pixels);

// Slope of the one-dimensional power spectrum of a w x w field (w a power of two), averaged
// over its rows and its columns (as transects of satellite images are analysed; Cahalan and
// Snider 1989), each transect with its mean removed and a Hann window, fitted on log power
// against log wavenumber on logarithmic bins between the wavelengths `longest_px` and
// `shortest_px`.
Fitted transectSpectrumSlope(const std::vector<double>& field, int w, double longest_px,
                             double shortest_px);

// Two renders of one view with cloud shadows on the ground (MODEL.md section 16) against a
// render without: where both show no cloud (coverage under 0.01 in both; the ground, and the
// sky, which is never shadowed), a pixel is in shadow where its luminance is under
// kShadowedRatio of the unshadowed render's (halfway between full sun and the sky light alone,
// groundLight). `agreement`: the fraction of
// `actual`'s shadowed pixels that `reference` also shadows; `mean_ratio_difference`: the mean
// |ratio(actual) - ratio(reference)| over those clear pixels; `shadowed`: the share of them
// `actual` shadows.
inline constexpr double kShadowedRatio = 0.65;
struct ShadowAgreement {
  double agreement = 0.0, mean_ratio_difference = 0.0, shadowed = 0.0;
  int clear_pixels = 0;
};
ShadowAgreement shadowAgreement(const FloatImage& actual, const FloatImage& reference,
                                const FloatImage& unshadowed);

}  // namespace nephele
