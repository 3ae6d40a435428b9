#pragma once
// What the files of EllipsoidRenderer share (ellipsoid_renderer.cpp: frames, batches, impostors
// and the centre order; ellipsoid_textures.cpp: the clouds' baked tables; ellipsoid_per_pixel.cpp:
// the per-pixel pass; ellipsoid_multipass.cpp: Elinas and Stuerzlinger's tiles).
#include <string>

#include "renderer/gl/gl_objects.h"
#include "renderer/render_settings.h"
#include "world/textures/solid_texture.h"

namespace nephele {
namespace ellipsoid_detail {

inline int nextPowerOfTwo(double x) {
  int p = 1;
  while (p < x && p < (1 << 20)) p *= 2;
  return p;
}

// A colour texture of `format` and `size`, sampled bilinearly and clamped at its edges, and a
// framebuffer that draws into it (the atlas, an impostor, the per-pixel pass's samples).
void createColourTarget(const GlApi& gl, GLenum format, glm::ivec2 size, const char* what,
                        GlObject& texture, GlObject& framebuffer);

// The key of a cloud texture as the frame's clouds name it, its scale and the settings it is
// drawn with included.
std::string textureKey(const SolidTextureSpec& spec, const RenderSettings& settings);

// Baked solid Gardner (MODEL.md section 2, "baked solid texture"): the sums SX - T0 and
// SY - T0 of the lower floor(n / 2) terms in one table over the period, of the upper terms in
// a second over the period of its lowest term, 2^m times shorter (m the lower count), each at
// 16 texels per cycle of its highest term (8 for a table of four terms, held to 128 a side).
// A table of t texels per cycle holds all its c terms on its first log2(t) - 1 levels and one
// fewer on each level above: GL's trilinear LOD then fades each term over the octave below its
// limit (the fade of section 2), and the upper table's terms are gone before the lower
// table's begin to fade. The shader adds the two tables' sums to T0 and takes
// T = k max(SX, 0) max(SY, 0). Five terms: 64^3 and 128^3 RG16F; six or seven: 128^3 twice,
// 18 MiB with their levels.
struct BakedSolidLayout {
  int coarse_terms, fine_terms;
  double fine_periods;  // periods of the fine table per period of the texture
};
BakedSolidLayout bakedSolidLayout(const GardnerTexture& gardner);

}  // namespace ellipsoid_detail
}  // namespace nephele
