#include "renderer/gl/ellipsoid_shaders.h"

#include "renderer/gl/shaders/ellipsoid_glsl.h"
#include "renderer/gl/sky_shaders.h"

namespace nephele {
namespace {

// The pieces, in renderer/gl/shaders/ellipsoid/ (embedded at build time: shaders/glsl.cmake).
// Fragment stages: the view chunk, the records, the cloud, then the program's main().
using glsl::ellipsoid::kCloud;          // hit, solid texture, limb, shading
using glsl::ellipsoid::kComposite;      // a tile drawn as a screen rectangle
using glsl::ellipsoid::kFusedCentre;    // fused, back to front by centre
using glsl::ellipsoid::kFusedPerPixel;  // fused, each pixel walks its bin's hits
using glsl::ellipsoid::kImpostor;       // a far cloud's impostor
using glsl::ellipsoid::kRecords;        // the per-ellipsoid record (both stages)
using glsl::ellipsoid::kTile;  // Elinas' tile passes (TILE_THRESHOLD, TILE_LIMB, TILE_COLOUR)
using glsl::ellipsoid::kVeil;  // in-cloud fog

// Behind a thick veil (MODEL.md section 15, "behind the veil"): the walk's result at every
// SHADING_RATE-th pixel in x and y (sample c at pixel c * SHADING_RATE), blended over the
// blocks of pixels whose four corner samples agree. The CPU sorts the blocks from the samples
// it reads back; the others are walked (kFusedRest).
using glsl::ellipsoid::kFusedBlend;

// A continuous view's heaps (MODEL.md section 15, "reuse across frames"): this frame's
// samples, at one pixel in SHADING_RATE^2 from u_sample_origin, are exact where they stand;
// every other pixel takes the last frame's heaps reprojected to it by its samples' distance,
// the camera's motion and the clouds' drift, kept within the range of the four samples around
// it, or the samples' blend where the last frame cannot vouch for it. Blended over the frame
// and written as it is to the next frame's history.
using glsl::ellipsoid::kFusedResolve;

// Vertex stages: the program's piece after #version (and the records where it reads them).
using glsl::ellipsoid::kFusedCentreVertex;  // one screen rectangle per ellipsoid, instanced
using glsl::ellipsoid::kImpostorVertex;     // a billboard
using glsl::ellipsoid::kRectsVertex;        // listed pixel rectangles
using glsl::ellipsoid::kTileVertex;         // the tessellated ellipsoid in its tile's frustum

}  // namespace

std::string EllipsoidPassLayout::key() const {
  std::string k = "e";
  k += char('0' + int(program));
  k += char('0' + int(texture));
  k += char('0' + int(term_filter));
  k += spotlight ? 'l' : '-';
  k += char('a' + int(air));
  k += specular ? 's' : '-';
  k += targets ? 't' : '-';
  k += history ? 'h' : '-';
  k += std::to_string(shading_rate);
  return k;
}

std::string ellipsoidVertexSource(const EllipsoidPassLayout& layout) {
  std::string s = "#version 450 core\n";
  switch (layout.program) {
    case EllipsoidProgram::kFusedCentre:
      s += kRecords;
      s += kFusedCentreVertex;
      return s;
    case EllipsoidProgram::kTileThreshold:
    case EllipsoidProgram::kTileLimb:
    case EllipsoidProgram::kTileColour:
      s += kRecords;
      s += kTileVertex;
      return s;
    case EllipsoidProgram::kFusedBlend:
    case EllipsoidProgram::kFusedResolve:
    case EllipsoidProgram::kFusedRest:
      return s + kRectsVertex;
    case EllipsoidProgram::kImpostor:
      return s + kImpostorVertex;
    default:
      return polygonVertexSource();
  }
}

std::string ellipsoidFragmentSource(const EllipsoidPassLayout& layout) {
  std::string s = "#version 450 core\n";
  s += airDefines(layout.air);
  if (layout.specular) s += "#define SPECULAR\n";
  if (layout.targets) s += "#define TARGETS\n";
  if (layout.history) s += "#define HISTORY\n";
  if (layout.spotlight) s += "#define SPOTLIGHT\n";
  if (layout.texture == SolidTextureKind::kProcedural) s += "#define PROCEDURAL\n";
  if (layout.texture == SolidTextureKind::kBakedGardner) s += "#define BAKED_GARDNER\n";
  if (layout.term_filter == TermFilter::kCut) s += "#define FILTER_CUT\n";
  if (layout.term_filter == TermFilter::kNone) s += "#define FILTER_NONE\n";
  switch (layout.program) {
    case EllipsoidProgram::kTileThreshold:
      s += "#define TILE_THRESHOLD\n";
      break;
    case EllipsoidProgram::kTileLimb:
      s += "#define TILE_LIMB\n";
      break;
    case EllipsoidProgram::kTileColour:
      s += "#define TILE_COLOUR\n";
      break;
    case EllipsoidProgram::kFusedSamples:
      // Sample c stands at pixel c * rate + u_sample_origin (0 but in a continuous view).
      s += "#define SAMPLE_DISTANCE\nuniform ivec2 u_sample_origin;\n#define FRAG_XY "
           "(floor(gl_FragCoord.xy) * " +
           std::to_string(layout.shading_rate) + ".0 + vec2(u_sample_origin) + 0.5)\n";
      break;
    case EllipsoidProgram::kFusedBlend:
    case EllipsoidProgram::kFusedResolve:
      s += "#define SHADING_RATE " + std::to_string(layout.shading_rate) + "\n";
      break;
    default:
      break;
  }
  s += viewShaderSource();
  if (layout.program == EllipsoidProgram::kVeil) return s + kVeil;
  if (layout.program == EllipsoidProgram::kImpostor) return s + kImpostor;
  s += kRecords;
  s += kCloud;
  switch (layout.program) {
    case EllipsoidProgram::kFusedCentre:
      return s + kFusedCentre;
    case EllipsoidProgram::kFusedPerPixel:
    case EllipsoidProgram::kFusedSamples:
    case EllipsoidProgram::kFusedRest:
      return s + kFusedPerPixel;
    case EllipsoidProgram::kFusedBlend:
      return s + kFusedBlend;
    case EllipsoidProgram::kFusedResolve:
      return s + kFusedResolve;
    case EllipsoidProgram::kTileComposite:
      return s + kComposite;
    default:
      return s + kTile;
  }
}

}  // namespace nephele
