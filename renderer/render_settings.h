#pragma once
// Speed-for-accuracy knobs of the GL renderer; each is measured against the CPU reference by
// bench/render_bench.
#include "world/formations/cloud_field.h"
#include "world/sea.h"
#include "world/textures/gardner_texture.h"

namespace nephele {

enum class TextureEvaluation {
  kAuto,        // baked for ellipsoids; a layer's clipmap filled over the frames after its first
  kBaked,       // Gardner's texture baked per layer into a mip chain of term truncations
  kProcedural,  // Gardner's sum of sines evaluated per fragment
};

enum class SkyPasses {
  kFused,      // background and every layer in one pass, composited in the shader
  kMultipass,  // a background pass, then one blended pass per layer (Elinas-style)
};

// Ellipsoid clouds (Gardner; Elinas and Stuerzlinger).
enum class EllipsoidPasses {
  kFused,      // one pass per ellipsoid straight to the screen: exact ray-quadric hit per
               // fragment over its screen rectangle, every term of eq. 8 and 11 at once
  kMultipass,  // Elinas: per-ellipsoid tiles in an atlas (threshold, limb, colour passes on a
               // tessellated ellipsoid), a shader pass applying 1/D, then tiles composited
};

enum class EllipsoidOrder {
  kCentre,    // back to front by distance to each ellipsoid's centre (Elinas)
  kPerPixel,  // each pixel composites the cloud's ellipsoids by the depth of their hits
};

enum class LimbEvaluation {
  kExact,      // g from the discriminant form per fragment (MODEL.md section 4)
  kSpotlight,  // Elinas: a radial 1 - rho^2 texture projected from the eye along the cone
};

enum class TileFormat { kRgba8, kFloat };

struct RenderSettings {
  SkyPasses sky_passes = SkyPasses::kFused;
  TextureEvaluation texture_evaluation = TextureEvaluation::kAuto;
  TermFilter term_filter = TermFilter::kFade;
  // Baked texture resolution per cycle of each level's highest term. Bilinear error falls as
  // 1/tpc^2 (mean 0.0075, 0.0020, 0.0005 for 4, 8, 16 on a close deck); cost rises with it
  // through texture cache traffic (18.3, 19.3, 23.6 ms for cirrus at 1280x1024).
  int bake_texels_per_cycle = 8;

  EllipsoidPasses ellipsoid_passes = EllipsoidPasses::kFused;
  EllipsoidOrder ellipsoid_order = EllipsoidOrder::kPerPixel;
  LimbEvaluation limb = LimbEvaluation::kExact;
  // Multipass tiles: 0 sizes each tile to its screen rectangle rounded up to a power of two;
  // a power of two from 8 to 1024 fixes every tile at that size.
  int tile_resolution = 0;
  TileFormat tile_format = TileFormat::kFloat;
  // Multipass meshes: 0 adapts the slices to keep the silhouette within half a pixel;
  // otherwise N slices by N stacks (Elinas used 10 x 10).
  int tessellation = 0;
  // Far clouds drawn from an impostor rendered once and reused while the view of the cloud
  // changes by less than impostor_tolerance_px pixels; 0 turns impostors off.
  double impostor_tolerance_px = 0.0;
  // Heaps of cloud fields (world/formations/cloud_field.h): the range drawn as ellipsoids
  // (`heap_range`, a far deck beyond) and the projected radius, in pixels, from which every
  // lobe of a heap is drawn (`heap_detail`).
  HeapDrawing heaps{};
  // The frame's work budget (withinEllipsoidBudget, world/scene.h; the reference has none): the
  // ellipsoids of largest projected size are drawn while they number at most `ellipsoid_budget`
  // and their footprints cover at most `ellipsoid_overdraw` views; 0 turns either off.
  double ellipsoid_budget = 65536.0;
  double ellipsoid_overdraw = 256.0;

  // Heaps at a reduced shading rate (MODEL.md section 15, "reduced rate"): the per-pixel pass
  // walks one pixel in heap_shading_rate^2 (1, 2 or 4 pixels between samples), and the samples'
  // bilinear blend in premultiplied colour brings them to full size. 1 walks every pixel.
  int heap_shading_rate = 1;
  // A continuous view's heaps (GlRenderer::setContinuousView; MODEL.md section 15, "reuse
  // across frames"): each frame walks one pixel in heap_refresh (1, 4 or 16), a different one
  // each frame, and reprojects the last frame to the others. 1 walks every pixel every frame.
  // Single renders, dataset samples and the first frame after a cut are always exact.
  int heap_refresh = 4;

  // The ground's cloud shadows (MODEL.md section 16): the map's texels a side (256 to 4096;
  // 0 draws no shadows), over the ground where the clouds' shadows fall, at most
  // ShadowMap::kMaxSide metres a side. Error against the exact shadow falls with its size.
  int shadow_map_size = 512;
  // Sky planes' shadows on the planes and the ground below them (MODEL.md section 16, "sky
  // planes"): each receiving pixel reads every plane above it once more. false leaves them out.
  bool plane_shadows = true;

  // The sea (MODEL.md section 18): the sines standing for its spectrum (`sea_waves`, 16 to
  // 128: fewer are faster, and their sum repeats sooner), and the probe of what it mirrors, its
  // width a share of the view's (`sea_probe_scale`, 0.25 to 2: the reference traces each
  // reflection).
  int sea_waves = kSeaComponents;
  double sea_probe_scale = 0.5;

  // Automaton clouds: the view march's step in lattice spacings (the lattice holds
  // samples_per_cell samples per cell edge). Larger steps are faster and blur thin edges.
  double volume_step = 1.0;

  // Cloud depth and the infrared band (renderer/frame.h) are traced on the CPU, one ray per
  // block of channel_divisor x channel_divisor pixels copied to the block: cost falls with its
  // square, error grows at cloud edges.
  int channel_divisor = 1;
};

// The CPU reference (MODEL.md section 7).
struct ReferenceSettings {
  int samples_per_axis = 4;        // supersampling grid per pixel
  int threads = 0;                 // 0: one per hardware thread
  HeapDrawing heaps{};             // as RenderSettings::heaps
  int label_divisor = 1;           // depth, cloud depth, object id: one centre ray per N x N block
  int sea_waves = kSeaComponents;  // as RenderSettings::sea_waves
};

}  // namespace nephele
