#pragma once
// GLSL for ellipsoid clouds: the fused passes (exact ray-quadric hit per fragment), the
// Elinas-Stuerzlinger tile passes and their composite, and the in-cloud veil.
#include <string>

#include "world/textures/gardner_texture.h"

namespace nephele {

enum class EllipsoidProgram {
  kFusedCentre,    // instanced screen rectangles, one per ellipsoid, back to front
  kFusedPerPixel,  // one rectangle per batch; each pixel walks its bin's hits front to back
  kFusedSamples,   // the same walk at one pixel in shading_rate^2, into the samples texture
  kFusedBlend,     // the samples' blend over listed blocks whose four corner samples agree
  kFusedRest,      // the walk over the other blocks
  kFusedResolve,   // a continuous view: the samples, and the last frame reprojected between
  kTileThreshold,  // Elinas pass 1: alpha = It - T1
  kTileLimb,       // Elinas pass 2: alpha -= (T2 - T1)(1 - g)
  kTileColour,     // Elinas colour pass: Gardner eq. 8, fogged
  kTileComposite,  // 1/D into alpha, tile drawn as a screen rectangle
  kVeil,           // in-cloud fog over the whole view
  kImpostor,       // a far cloud's impostor drawn as a billboard
};

enum class SolidTextureKind { kProcedural, kBakedGardner, kTable };

struct EllipsoidPassLayout {
  EllipsoidProgram program = EllipsoidProgram::kFusedCentre;
  SolidTextureKind texture = SolidTextureKind::kBakedGardner;
  TermFilter term_filter = TermFilter::kFade;
  bool spotlight = false;  // g from the projected radial texture instead of the exact form
  unsigned air = 0;        // the media of the air (airMedia, world/scene.h)
  bool specular = false;
  bool targets = false;
  bool history = false;  // kFusedPerPixel: also written to a continuous view's history
  int shading_rate = 1;  // kFusedSamples, kFusedBlend and kFusedRest: pixels between samples

  std::string key() const;
};

// Coverage past which a pixel counts as opaque: the per-pixel pass stops compositing, and a
// veil this thick hides the frame behind it (what lies behind adds under 1/1024).
inline constexpr double kOpaqueCoverage = 1.0 - 1.0 / 1024.0;

// Behind the in-cloud veil (MODEL.md section 15, "behind the veil"), which shows a fraction
// `seen` of the frame drawn under it: the per-pixel pass may err by kVeiledTolerance / seen
// in each premultiplied channel, so that the final image errs by at most kVeiledTolerance.
// Where that comes to kVeiledSamplingFrom or more the pass walks one pixel in
// kVeiledShadingRate^2 and blends those samples wherever the four around a pixel agree to
// within it; the opacity cut moves likewise, to 1 - (1 - kOpaqueCoverage) / seen.
inline constexpr double kVeiledTolerance = 1.0 / 256.0;
inline constexpr double kVeiledSamplingFrom = 1.0 / 128.0;
inline constexpr int kVeiledShadingRate = 4;

// Per-ellipsoid record: RGBA32F texels of a buffer texture.
inline constexpr int kEllipsoidRecordVec4s = 19;
// Texture units.
inline constexpr int kBinTextureUnit = 7;
inline constexpr int kBinItemTextureUnit = 8;
inline constexpr int kRecordTextureUnit = 13;
// Side of the square screen bins of the per-pixel pass, pixels.
inline constexpr int kPerPixelBinSize = 8;
inline constexpr int kVolumeTextureUnit = 9;
inline constexpr int kSpotlightTextureUnit = 10;
inline constexpr int kAtlasTextureUnit = 11;
inline constexpr int kImpostorTextureUnit = 12;
inline constexpr int kSamplesTextureUnit = 12;        // no program reads both
inline constexpr int kSampleDistanceTextureUnit = 4;  // kFusedResolve's
inline constexpr int kHistoryTextureUnit = 5;
inline constexpr int kRectTextureUnit = 6;
inline constexpr int kFineVolumeTextureUnit = 14;
inline constexpr int kTargetColourUnit = 14;  // matches the view chunk's bindings
inline constexpr int kTargetDistanceUnit = 15;

std::string ellipsoidVertexSource(const EllipsoidPassLayout& layout);
std::string ellipsoidFragmentSource(const EllipsoidPassLayout& layout);

}  // namespace nephele
