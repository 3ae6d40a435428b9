#pragma once
// The GL renderer: opaque targets, then the sky background, cloud layers and ellipsoid
// clouds composited back to front into a framebuffer object, then read back.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"
#include "renderer/frame.h"
#include "renderer/frame_plan.h"
#include "renderer/frame_stats.h"
#include "renderer/gl/automaton_renderer.h"
#include "renderer/gl/ellipsoid_renderer.h"
#include "renderer/gl/gl_objects.h"
#include "renderer/gl/gl_platform.h"
#include "renderer/gl/gpu_pass_timer.h"
#include "renderer/gl/layer_clipmap.h"
#include "renderer/gl/shadow_map.h"
#include "renderer/gl/sky_shaders.h"
#include "renderer/gl/target_renderer.h"
#include "renderer/render_settings.h"
#include "world/scene.h"

namespace nephele {

class LayerTexture;
class ScreenLines;

class GlRenderer {
 public:
  // Borrows the platform, whose context must stay current on this thread.
  explicit GlRenderer(const GlPlatform& platform);
  ~GlRenderer();

  // Linear float RGB plus coverage (for EXR and for measuring error).
  FloatImage renderFloat(const Scene& scene, const RenderSettings& settings);
  // The channels `request` asks for (renderer/frame.h): colour, coverage and visibility from
  // the composited frame, depth and object id from the target pass and the ground plane, cloud
  // depth traced on the CPU (RenderSettings::channel_divisor).
  Frame renderFrame(const Scene& scene, const RenderSettings& settings,
                    const FrameRequest& request);
  // sRGB-encoded bytes, rows bottom-up as GL reads them (PNG, JPEG, TIFF).
  Srgb8Image renderSrgb8(const Scene& scene, const RenderSettings& settings);

  // The platform floor: one constant-colour full-screen pass, blended, and its readback into
  // the 8-bit target renderSrgb8 uses. Benchmarks print frame times as multiples of it, since
  // absolute times on shared machines vary by 30 % between runs.
  Srgb8Image renderFloor(int width, int height);

  // What the last frame did: passes, ellipsoids drawn and culled, terms evaluated.
  const FrameStats& lastFrameStats() const { return stats_; }

  // Allocates the target a width x height frame needs (linear float or 8-bit sRGB) and says,
  // before any work, when this GL cannot: what a platform can allocate depends on its memory
  // limits, not only on GL_MAX_RENDERBUFFER_SIZE. Empty when the target is ready.
  // `targets`: the frame draws targets (the scene has some, or depth or object ids are asked),
  // which need target layers of the same size.
  std::string reserveTarget(int width, int height, bool linear, bool targets);

  // The view that the frames from now on belong to, one of a stream that moves continuously
  // (a subscription, a host's channel), or empty (the default) when every frame must be the
  // exact one. A continuous view's heaps reuse its last frame (RenderSettings::heap_refresh,
  // MODEL.md section 15, "reuse across frames"); its first frame, and the first after a cut,
  // are exact.
  void setContinuousView(std::string view) { continuous_view_ = std::move(view); }
  // Far-cloud impostors rendered since construction (each reuse saves one).
  int impostorRenders() const { return ellipsoids_.impostorRenders(); }
  // A flag another thread may raise to cancel the frame being rendered; a cancelled frame's
  // image is incomplete and lastFrameCancelled() says so; `alive` is called wherever the flag
  // is read (EllipsoidRenderer::setCancel).
  void setCancel(const std::atomic<bool>* flag, std::function<void()> alive = {}) {
    ellipsoids_.setCancel(flag, std::move(alive));
  }
  bool lastFrameCancelled() const { return ellipsoids_.cancelled(); }
  // Automaton volume uploads since construction (one per keyframe change of a cloud).
  int volumeUploads() const { return automata_.uploads(); }

 private:
  enum class TargetFormat { kFloat, kSrgb8 };
  // A layer's texture, built once and kept while frames draw its layer (baked, a while longer:
  // kKeptTextures).
  struct CachedTexture {
    std::unique_ptr<LayerTexture> source;
    std::string key;               // textureKey: the clipmap of a texture is kept under it too
    GlObject texture;              // made on first use by a pass that samples it
    std::uint64_t last_frame = 0;  // the frame that last drew its layer
  };
  // Layer textures no frame draws any more are dropped, but for the kKeptTextures drawn most
  // recently: a dataset's samples come back to a few far-deck textures (cloud_field.h,
  // farDeck), each a bake of tens of milliseconds.
  static constexpr std::size_t kKeptTextures = 8;
  struct LayerSlot {
    const CloudLayer* layer;
    CachedTexture* texture;
    LayerKind kind;
    ClipmapView clipmap;  // kClipmapGardner: the rings around this frame's camera
  };

  // Which layers a view's sky passes draw on each side of the camera, back to front.
  struct LayerSides {
    std::vector<LayerSlot> above, below;
  };
  // A cloud (an ellipsoid cloud of the view's list, or an automaton) in one band of the
  // compositing order, with the band's window.
  struct CloudEntry {
    bool automaton;
    std::size_t index;
    int band;
    double distance;
    AltitudeBand window;
  };

  // The frame's plan (renderer/frame_plan.h; returned, for the channels the CPU adds from the
  // same plan, with the tracer's sea probe when `sea_eye`), then its views drawn: the sea's
  // probe, then the view; its CPU stages and GPU passes timed into stats_.times.
  static FramePlanRequest planRequest(const RenderSettings& settings, bool sea_eye);
  std::unique_ptr<FramePlan> drawFrame(const Scene& scene, const RenderSettings& settings,
                                       TargetFormat format, bool sea_eye = false);
  // The drawn float target, top row first.
  FloatImage readFloat(int width, int height);
  // What the sea mirrors, drawn into sea_probe_texture_ before a view that shows the sea
  // (MODEL.md section 18); the sky pass's sea uniforms read it.
  void drawSeaProbe(const FramePlan& plan, const RenderSettings& settings);
  // One view of a plan, in its passes: targets, the in-cloud veil, the layers and their
  // clipmaps, then the sky and the clouds band by band (drawBands).
  void drawView(const ViewPlan& view, const RenderSettings& settings, TargetFormat format);
  bool drawTargetsPass(const ViewPlan& view);  // false: none drawn
  void beginView(const Camera& camera, TargetFormat format);
  void endView(const Veil& veil);
  LayerSides layerSides(const ViewPlan& view, const RenderSettings& settings);
  void prepareClipmaps(const ViewPlan& view, const RenderSettings& settings, LayerSides& sides);
  std::vector<CloudEntry> cloudOrder(const ViewPlan& view, const LayerSides& sides);
  void drawBands(const ViewPlan& view, const RenderSettings& settings, const LayerSides& sides,
                 const std::vector<CloudEntry>& clouds, const Veil& veil, bool targets);
  void setSeaUniforms(GLuint program, const Scene& scene, const RenderSettings& settings);
  // Waits for the frame's passes, collects their times, and reads the target back.
  void finishAndRead(int width, int height, GLenum type, void* out);
  // Background (if asked) and the given layers, fused or one pass per layer.
  void drawSkyGroup(const Scene& scene, const RenderSettings& settings,
                    const std::vector<LayerSlot>& above, const std::vector<LayerSlot>& below,
                    bool background, bool targets);
  // The fused sky passes: one per side of the horizon, cut along far decks' holes.
  void drawFusedSky(const Scene& scene, const RenderSettings& settings, const SkyPassLayout& base,
                    const ScreenLines& lines, const std::vector<LayerSlot>& above,
                    const std::vector<LayerSlot>& below, bool background);
  void drawSkyPass(const Scene& scene, const RenderSettings& settings, const SkyPassLayout& layout,
                   const std::vector<LayerSlot>& slots, const std::vector<glm::vec2>& polygon);
  // Slot `slot` of the program's arrays, its table on texture unit `unit`.
  void setSlotUniforms(GLuint program, int slot, int unit, const LayerSlot& layer,
                       const Scene& scene, const RenderSettings& settings);
  void prepareTarget(int width, int height, TargetFormat format);
  bool allocateTarget(int width, int height, TargetFormat format);
  void readPixels(int width, int height, GLenum type, void* out) const;
  GLuint program(const SkyPassLayout& layout);
  CachedTexture& cachedTexture(const LayerTextureSpec& spec, const RenderSettings& settings);
  GLuint gpuTexture(CachedTexture& cached, const RenderSettings& settings);

  const GlApi& gl_;
  GlObject vertex_array_;
  GlObject framebuffer_;
  GlObject colour_buffer_;
  int target_width_ = 0;
  int target_height_ = 0;
  TargetFormat target_format_ = TargetFormat::kFloat;
  std::map<std::string, GlObject> programs_;
  // The frame's layers that cast shadows (castingPlanes; MODEL.md section 16, "sky planes"):
  // every sky pass evaluates them above its planes and the ground.
  std::vector<LayerSlot> casters_;
  static constexpr int kCasterUnit = 16;  // their tables' texture units, up from here
  std::string continuous_view_;
  // The sea's probe of this frame, and the last sea's waves.
  bool sea_probe_ = false;
  GlObject sea_probe_texture_;
  int sea_probe_width_ = 0, sea_probe_height_ = 0;
  glm::dvec3 sea_probe_right_{1.0, 0.0, 0.0}, sea_probe_up_{0.0, 0.0, 1.0},
      sea_probe_forward_{0.0, 1.0, 0.0};
  struct SeaWaves {
    Sea sea;
    int waves;
    SeaSurface surface;
  };
  std::optional<SeaWaves> sea_surface_;
  std::map<std::string, CachedTexture> textures_;
  std::uint64_t frame_ = 0;  // frames drawn
  GlObject floor_program_;
  FrameStats stats_;
  GpuPassTimer timer_;
  EllipsoidRenderer ellipsoids_;
  AutomatonRenderer automata_;
  LayerClipmaps clipmaps_;
  TargetRenderer targets_;
  ShadowMap shadow_map_;
  // The frame's shadows of the clouds on what lies below them (MODEL.md section 16), the plan's,
  // set while drawFrame draws.
  SceneSunlight sunlight_;
};

}  // namespace nephele
