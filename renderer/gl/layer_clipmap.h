#pragma once
// Clipmaps of layer textures that never repeat (MODEL.md section 2, "Clipmap"). A layer whose
// Gardner texture is rotated or jittered cannot be held in a periodic table, so per pixel its
// sines cost 11 to 15 times the clear frame; here it is evaluated once into rings of texels that
// follow the camera through the layer's own plane, and the sky pass reads them. Ring l holds
// the texture truncated to n - l terms (the terms the term filter keeps at its texel size), on a
// lattice twice as coarse as ring l - 1's, N x N texels around the point under the camera;
// texel index k of the lattice is stored at k mod N, so when the camera moves only the strips
// it uncovers are evaluated (a toroidal update), the rest of each ring stays.
#include <cstdint>
#include <list>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/gl/gl_objects.h"

namespace nephele {

class GardnerTexture;
struct FrameStats;

// Gardner's per-term uniforms of slot `slot` of a sky program (u_fx ... u_k), with the phases
// taken at texture-space point `origin` (metres, drift removed) in double (MODEL.md section 2's
// precision rule): the shader sees offsets from `origin` only.
void setLayerGardnerUniforms(const GlApi& gl, GLuint program, int slot, const GardnerTexture& g,
                             glm::dvec2 origin);

// What the sky pass needs to read one clipmap (shaders/sky/layers.glsl, clipmapValue).
struct ClipmapView {
  GLuint texture = 0;             // GL_TEXTURE_2D_ARRAY, one layer per ring
  int size = 0;                   // N
  int rings = 0;                  // n, the texture's terms
  glm::dvec2 texel_m{0.0};        // ring 0's texel, metres along X and Y
  std::vector<glm::vec2> offset;  // per ring: the camera's lattice coordinate modulo N
  double constant = 0.0;          // T with no term
  // The finest ring from which every coarser ring holds every texel (rings: none yet). The sky
  // pass reads no finer ring: a continuous view's clipmap being filled shows the coarse terms
  // first, as a streamed texture shows its coarse mip levels, and no frame switches to another
  // program; other renders read the sines until it is complete.
  int finest = 0;
  bool usable() const { return finest < rings; }
  bool complete() const { return finest == 0; }
};

class LayerClipmaps {
 public:
  explicit LayerClipmaps(const GlApi& gl);
  ~LayerClipmaps();

  // The clipmap of texture `g` (cached under `key`) around texture-space point `eye`, with
  // N = `size` texels a side: its strips refreshed where the eye moved since the clipmap was last
  // read, then up to `budget` texels of the rings not yet filled (a new clipmap is filled over
  // the frames that follow, so that no frame pays for all of it; the view says when it is
  // complete). A clipmap first asked for is only noted, with nothing evaluated, when `wait` is
  // set: a view that is not drawn again (a single render, a dataset's sample) never pays for one.
  // Otherwise the coarsest ring is filled whole at once, so the clipmap is usable from its first
  // frame (that ring holds one term a texel, a fraction of a frame's sines).
  // The caller restores its framebuffer, viewport and program afterwards.
  const ClipmapView& prepare(const std::string& key, const GardnerTexture& g, glm::dvec2 eye,
                             int size, std::int64_t budget, bool wait, FrameStats& stats);
  void beginFrame() { ++frame_; }
  void endFrame();  // drops the clipmaps no recent frame read

  // Texels a side for a view `height` pixels high: a ring is read at full weight out to N/4
  // texels from its centre, where its texel is 4 d / N metres at distance d. Looking straight at
  // a layer from height h through a view of half-angle a, a pixel at the edge (d = h tan a) has
  // a footprint of about 2 h tan a (1 + tan^2 a) / height, so N = 2 height keeps the rings as fine
  // as the pixels for any angle; an oblique view needs less. Rounded up to a power of two from
  // 256 and at most 1024 (2 MiB a ring): taller views lose up to an octave at the edges.
  static int sizeFor(int height);

  // Texels evaluated since construction (the bake's cost, for benchmarks).
  std::int64_t texelsBaked() const { return texels_baked_; }

 private:
  struct Clipmap {
    GlObject texture;
    int size = 0, rings = 0;
    glm::dvec2 texel_m{0.0};
    std::vector<glm::i64vec2> centre;  // per ring, lattice index of the window's middle
    // Per ring, the storage rows filled so far (0 to N): rows below it hold their texels, and
    // the strips a move uncovers are filled whole, so the rows stay valid as the eye moves.
    std::vector<int> rows;
    bool placed = false;  // centre holds the window's place
    std::uint64_t last_frame = 0;
    ClipmapView view;
  };
  Clipmap& choose(const std::string& key, const GardnerTexture& g, glm::dvec2 eye, int size);
  // Evaluates storage rectangle [x0, x1) x [y0, y1) of ring `ring`.
  void bake(Clipmap& c, const GardnerTexture& g, int ring, glm::ivec4 rect);
  // Makes the bake program and c's texture when missing, and binds them for bake.
  void bindForBaking(Clipmap& c, int size);

  const GlApi& gl_;
  GlObject program_;
  GlObject framebuffer_;
  std::map<std::string, std::list<Clipmap>> clipmaps_;
  std::uint64_t frame_ = 0;
  std::int64_t texels_baked_ = 0;
};

}  // namespace nephele
