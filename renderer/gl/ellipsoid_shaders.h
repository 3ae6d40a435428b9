#pragma once
// GLSL for ellipsoid clouds: the fused passes (exact ray-quadric hit per fragment), the
// Elinas-Stuerzlinger tile passes and their composite, and the in-cloud veil.
#include <string>

#include "world/textures/gardner_texture.h"

namespace nephele {

enum class EllipsoidProgram {
  kFusedCentre,    // instanced screen rectangles, one per ellipsoid, back to front
  kFusedPerPixel,  // one rectangle per batch; each pixel walks its bin's hits front to back
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
  bool air = false;
  bool specular = false;
  bool targets = false;

  std::string key() const;
};

// Coverage past which a pixel counts as opaque: the per-pixel pass stops compositing, and a
// veil this thick hides the frame behind it (what lies behind adds under 1/1024).
inline constexpr double kOpaqueCoverage = 1.0 - 1.0 / 1024.0;

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
inline constexpr int kFineVolumeTextureUnit = 14;
inline constexpr int kTargetColourUnit = 14;  // matches the view chunk's bindings
inline constexpr int kTargetDistanceUnit = 15;

std::string ellipsoidVertexSource(const EllipsoidPassLayout& layout);
std::string ellipsoidFragmentSource(const EllipsoidPassLayout& layout);

}  // namespace nephele
