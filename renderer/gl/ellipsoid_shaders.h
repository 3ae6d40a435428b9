#pragma once
// GLSL for ellipsoid clouds: the fused passes (exact ray-quadric hit per fragment), the
// Elinas-Stuerzlinger tile passes and their composite, and the in-cloud veil.
#include <string>

#include "world/textures/gardner_texture.h"

namespace nephele {

enum class EllipsoidProgram {
  kFusedCentre,    // instanced screen rectangles, one per ellipsoid, back to front
  kFusedPerPixel,  // one rectangle per cloud; each pixel sorts the cloud's hits by depth
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
  bool fog = false;
  bool specular = false;
  bool targets = false;

  std::string key() const;
};

// Per-ellipsoid record in the shader storage buffer (std430, 16 vec4).
inline constexpr int kEllipsoidRecordVec4s = 17;
// Storage-buffer and texture binding points.
inline constexpr int kEllipsoidBufferBinding = 0;
inline constexpr int kBinBufferBinding = 1;
inline constexpr int kBinItemBufferBinding = 2;
// Side of the square screen bins of the per-pixel pass, pixels.
inline constexpr int kPerPixelBinSize = 16;
inline constexpr int kVolumeTextureUnit = 9;
inline constexpr int kSpotlightTextureUnit = 10;
inline constexpr int kAtlasTextureUnit = 11;
inline constexpr int kImpostorTextureUnit = 12;
inline constexpr int kTargetColourUnit = 14;  // matches the view chunk's bindings
inline constexpr int kTargetDistanceUnit = 15;

std::string ellipsoidVertexSource(const EllipsoidPassLayout& layout);
std::string ellipsoidFragmentSource(const EllipsoidPassLayout& layout);

}  // namespace nephele
