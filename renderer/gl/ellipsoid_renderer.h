#pragma once
// Ellipsoid clouds on the GL: visible ellipsoids culled and ordered on the CPU in double,
// then drawn either fused (exact per-fragment hits) or with Elinas and Stuerzlinger's tiles.
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/frame_plan.h"
#include "renderer/frame_stats.h"
#include "renderer/gl/ellipsoid_shaders.h"
#include "renderer/gl/gl_objects.h"
#include "renderer/gl/gpu_pass_timer.h"
#include "renderer/gl/view_uniforms.h"
#include "renderer/render_settings.h"
#include "world/formations/cloud_shadow.h"
#include "world/scene.h"

namespace nephele {

// Where a pass draws: the framebuffer, its size, and the fraction of what is drawn there that
// the final image shows (the transmittance of the in-cloud veil drawn over the frame; 1 for an
// impostor, which later frames reuse under other veils).
struct PassTarget {
  GLuint framebuffer = 0;
  int width = 0;
  int height = 0;
  double seen = 1.0;
};

// One ellipsoid as the shaders see it (EllipsoidRecord in shaders/ellipsoid/records.glsl).
struct EllipsoidRecord {
  glm::vec4 v[kEllipsoidRecordVec4s];
};

// Everything the GPU needs for one ellipsoid seen from `camera`; false when it cannot show
// (behind the eye, off screen, the eye inside it, or faded out by the in-cloud model).
// `centre_distance` is the back-to-front sort key. The spotlight rows are filled only when
// `spotlight` asks for them.
bool makeEllipsoidRecord(const Ellipsoid& ellipsoid, const Camera& camera, bool spotlight,
                         EllipsoidRecord& out, double& centre_distance);

class EllipsoidRenderer {
 public:
  explicit EllipsoidRenderer(const GlApi& gl);
  ~EllipsoidRenderer();

  // Starts a frame: marks cached textures unused until a cloud asks for them again; the
  // frame's passes and ellipsoids are counted into `stats`.
  // `continuous_view` names the view a continuous stream of frames is drawn for (empty: an
  // exact frame): its heaps reuse the last frame's (RenderSettings::heap_refresh).
  void beginFrame(FrameStats& stats, GpuPassTimer& timer, const std::string& continuous_view = {});
  void endFrame();

  // Draws clouds `indices` of the view's list (back to front by their distance) "over" what
  // `target` holds, blending premultiplied. `targets_drawn`: the target colour and distance
  // textures are bound. A far cloud may be drawn from its impostor
  // (RenderSettings::impostor_tolerance_px); the others are drawn in batches of clouds that
  // look alike (same texture, drift and shading), each batch as one (the per-pixel pass
  // composites every hit of the batch in depth order; the centre and multipass passes blend
  // its ellipsoids back to front). Only the surfaces in `band` are drawn, so that a layer
  // can cut through the clouds.
  void drawClouds(const ViewPlan& view, const std::vector<std::size_t>& indices,
                  const RenderSettings& settings, const PassTarget& target, bool targets_drawn,
                  const AltitudeBand& band = {});

  // The sunlight the clouds above let through (MODEL.md section 16), which each lobe takes at
  // its centre, its own heap left out; null or empty: none. It must outlive the frames drawn
  // with it.
  void setSunlight(const SceneSunlight* sunlight) { sunlight_ = sunlight; }

  // Impostors rendered so far (for measurement and tests).
  int impostorRenders() const { return impostor_renders_; }

  // A flag another thread may raise to cancel the frame being drawn (a daemon stopping,
  // docs/RELIABILITY.md). It is read between batches, every kCancelRecords ellipsoids while
  // records are made, and, in a heavy batch, after each part of it is queued: the per-pixel
  // pass in bands of about kCancelWork hit tests, the centre pass in groups of
  // kCancelInstances. Light batches draw as without it, but for the same pacing between
  // batches once their queued work reaches kCancelWork. Before the flag is read the part
  // queued before the last has finished (paceQueued), so a cancel waits for two parts at
  // most. Once raised the rest of the frame's ellipsoids are skipped and cancelled() says so
  // until the next beginFrame.
  // `alive`, if given, is called at each of those points: the frame is making progress (a
  // daemon's watchdog heartbeat).
  void setCancel(const std::atomic<bool>* flag, std::function<void()> alive = {}) {
    cancel_ = flag;
    alive_ = std::move(alive);
  }
  bool cancelled() const { return cancelled_; }

  // The in-cloud veil at the eye (MODEL.md section 4), and the pass that draws it over the
  // whole frame (none when its opacity is 0).
  Veil veil(const ViewPlan& view, const RenderSettings& settings);
  void drawVeil(const Veil& veil);

 private:
  static constexpr std::size_t kCancelRecords = 65536;
  // A batch's records are computed on up to this many threads, one per this many ellipsoids.
  static constexpr int kRecordThreads = 8;
  static constexpr int kRecordsPerThread = 512;
  // Half of the 2^25 hit tests a cancel may wait for: two parts are in flight (paceQueued).
  static constexpr std::int64_t kCancelWork = std::int64_t(1) << 24;
  static constexpr std::size_t kCancelInstances = 16384;
  // A continuous view's history is kept while its view draws at least once in
  // kKeptHistoryFrames frames of the renderer, and reused across a step of at most kCutStep_m,
  // a turn of at most kCutTurn_deg and at most kCutTime_s of world time: more is a cut.
  static constexpr std::uint64_t kKeptHistoryFrames = 64;
  static constexpr double kCutStep_m = 500.0;
  static constexpr double kCutTurn_deg = 10.0;
  static constexpr double kCutTime_s = 2.0;
  bool stopNow() {
    if (alive_) alive_();
    if (!cancelled_ && cancel_ && cancel_->load(std::memory_order_relaxed)) cancelled_ = true;
    return cancelled_;
  }
  // Waits for the part of heavy work queued before the one just queued (a fence), not for
  // that one: the GPU has it to work on while the CPU waits and queues the next, where a
  // glFinish would drain it between parts.
  void paceQueued();
  void dropPartFence();

  // A cloud texture as the frame's clouds name it (its scale included), and the baked table it
  // samples, which clouds differing only in scale share (bakedTableSpec).
  struct CachedTexture {
    std::unique_ptr<SolidTexture> source;
    std::string table_key;
    bool used = false;
  };
  struct BakedTable {
    GlObject texture;
    GlObject fine;  // Gardner's upper terms (bakedSolidLayout); none for a Perlin table
    std::uint64_t last_frame = 0;  // the frame that last sampled it
  };
  // Tables kept beyond the frame that last used them (least recently used first out): a
  // dataset's samples, or a daemon's genera coming and going, reuse them instead of baking
  // them again. Six terms: two RG16F tables of 128^3, 18 MiB with their levels.
  static constexpr std::size_t kKeptTables = 8;
  struct Tile {
    int record;  // index into the batch's records
    int width, height;
    int x = 0, y = 0;
  };

  // A far cloud rendered once from `eye` into a texture and shown as a billboard through
  // its bounding sphere's centre, facing that eye.
  struct Impostor {
    std::string key;  // everything the picture depends on besides the eye
    glm::dvec3 eye{0.0}, centre{0.0}, right{0.0}, up{0.0};
    double half_size = 0.0;  // billboard half-extent, metres
    int size = 0;            // texels a side
    GlObject texture, framebuffer;
    bool used = false;
  };

  // Clouds `indices`, which look alike, drawn from their ellipsoids in one batch; `batch` is
  // their look (empty for an impostor's picture, which has no history).
  void drawDirect(const ViewPlan& view, const std::vector<std::size_t>& indices,
                  const RenderSettings& settings, const PassTarget& target, bool targets_drawn,
                  const AltitudeBand& band, const std::string& batch);
  // False when the cloud is too near for an impostor; then the caller draws it directly.
  bool drawImpostor(const ViewPlan& view, std::size_t index, const RenderSettings& settings,
                    const PassTarget& target, bool targets_drawn, const AltitudeBand& band);
  // Draws the cloud alone into its impostor's texture, from the eye towards its centre.
  void renderImpostor(const ViewPlan& plan, std::size_t index, int size,
                      const RenderSettings& settings, const PassTarget& target, Impostor& impostor);
  GLuint program(const EllipsoidPassLayout& layout);
  CachedTexture& cachedTexture(const SolidTextureSpec& spec, const RenderSettings& settings);
  // Binds the texture's tables (the baked Gardner sums, or a Perlin table), baking them first
  // if they are not kept.
  void bindTables(CachedTexture& cached);
  const IndexedMesh& sphereMesh(int slices);  // cached per tessellation
  GLuint spotlightTexture();
  void setCloudUniforms(GLuint program, const Scene& scene, const EllipsoidCloud& cloud,
                        const CachedTexture& texture, SolidTextureKind kind,
                        const AltitudeBand& band);
  // Binds to `unit` a buffer texture of `format` holding `bytes` of `data`.
  void bindFrameTexture(int unit, GLenum format, const void* data, std::size_t bytes);
  void uploadRecords(const std::vector<EllipsoidRecord>& records);
  void drawTiles(const Scene& scene, const EllipsoidCloud& cloud, CachedTexture& texture,
                 const EllipsoidPassLayout& base, const RenderSettings& settings,
                 std::vector<EllipsoidRecord>& records, const PassTarget& target,
                 const AltitudeBand& band);
  void renderAtlasBatch(const Scene& scene, const EllipsoidCloud& cloud,
                        const CachedTexture& texture, const EllipsoidPassLayout& base,
                        const RenderSettings& settings, std::vector<EllipsoidRecord>& records,
                        std::vector<Tile>& tiles, const PassTarget& target,
                        const AltitudeBand& band);
  // The atlas's tiles composited over `target`.
  void compositeAtlasTiles(const Scene& scene, const EllipsoidCloud& cloud,
                           const CachedTexture& texture, const EllipsoidPassLayout& base,
                           const std::vector<EllipsoidRecord>& records,
                           const std::vector<Tile>& tiles, const PassTarget& target,
                           const AltitudeBand& band);
  void prepareAtlas(TileFormat format);
  // The per-pixel pass's samples texture (RGBA16F) and their distances (R32F), and their
  // framebuffer, at `size`.
  void prepareSamples(glm::ivec2 size);
  // A continuous view's heaps of one band as last drawn (MODEL.md section 15, "reuse across
  // frames"): the premultiplied colour and coverage of its batches without the layers, at the
  // frame's size, in two textures that take turns being read and written.
  struct HeapHistory {
    std::string key;  // what the band is: its batches' looks and its slabs
    GlObject colour[2], framebuffer[2];
    glm::ivec2 size{0};
    int last = 0;              // the texture holding the last frame
    bool valid = false;        // it holds a frame this one may reuse
    std::uint64_t frames = 0;  // frames resolved since the exact one: the sample offset
    std::uint64_t used = 0;    // the renderer frame that last drew it
    Camera camera;             // the last frame's
    double time_s = 0.0;
    glm::dvec2 drift{0.0};  // the heaps' drift then (heapDrift)
  };
  // The history of the batches drawn in the `ordinal`-th drawClouds call of this frame of the
  // continuous view, valid when the same batches were drawn last time from a camera near
  // enough to reuse.
  HeapHistory& heapHistory(const Scene& scene, const std::string& key, glm::ivec2 size);
  // A continuous view's batches of one drawClouds call share one history, one grid of samples
  // and one resolve over the bins any of them overlaps (MODEL.md section 15, "reuse across
  // frames"): each batch walks its samples over the others' ("over" in colour, the nearest
  // distance), and the call ends with finishBand.
  struct BandReuse {
    HeapHistory* history = nullptr;  // none: not a continuous view, or targets drawn
    bool reuse = false;              // the history is valid: this frame samples and resolves
    int rate = 1;                    // its samples stand one pixel in rate x rate
    glm::ivec2 origin{0}, size{0};   // the pixel of sample (0, 0), and the grid's size
    int bins_x = 0;                  // the frame's bins a row
    std::vector<std::uint8_t> bins;  // the frame's bins some batch's ellipsoids overlap
    bool cancelled = false;          // a batch was cancelled: nothing is resolved or kept
    bool broken = false;             // a batch drew straight into the frame: not kept
  };
  void beginBand(const Scene& scene, const std::string& key, const PassTarget& target,
                 const RenderSettings& settings);
  // `draw` over the frame and into the band's next history; false when it was cancelled.
  bool drawWithHistory(const PassTarget& target, bool accumulate,
                       const std::function<bool()>& draw);
  // A sample no batch hit (its distance texture's clear value; the resolve's "no hit").
  static constexpr float kNoSampleDistance = 3.4e38f;
  void finishBand(const Scene& scene, const PassTarget& target);
  BandReuse band_;

  // The parts of drawDirect. Visible ellipsoids with the back-to-front key (the front-to-back
  // key, the nearest a hit can be, is the record's order.z).
  struct Visible {
    double centre_distance;
    EllipsoidRecord record;
  };
  // What the passes of one batch share.
  struct Batch {
    const Scene& scene;
    const EllipsoidCloud& cloud;  // the first of the batch, whose look stands for all
    CachedTexture& texture;
    const RenderSettings& settings;
    const PassTarget& target;
    const AltitudeBand& band;
    EllipsoidPassLayout base;
    HeapHistory* history;  // one of a continuous view's band of batches, or null
    bool targets_drawn;
  };
  // The per-pixel pass's screen bins over a batch's area (absolute bin indices in x, y, z, w
  // = first x, first y, last x, last y), each its first item and count, and the items: records
  // in the order drawn.
  struct BinLists {
    glm::ivec4 area{0};
    int bins_x = 0, bins_y = 0;
    std::int64_t listed = 0;  // entries over all bins
    std::vector<glm::ivec2> bins;
    std::vector<GLint> items;
    // No two ellipsoids share a bin (and no history is kept): the centre pass draws the same.
    bool centre_suffices = false;
    glm::ivec2& at(int x, int y) { return bins[std::size_t(y - area.y) * bins_x + (x - area.x)]; }
    const glm::ivec2& at(int x, int y) const {
      return bins[std::size_t(y - area.y) * bins_x + (x - area.x)];
    }
  };
  // The batch's records, made on up to kRecordThreads threads; `total` its ellipsoids.
  std::vector<Visible> visibleRecords(const ViewPlan& view, const std::vector<std::size_t>& indices,
                                      bool spotlight, int& total);
  std::vector<EllipsoidRecord> orderedRecords(std::vector<Visible>& visible, bool front_to_back);
  EllipsoidPassLayout batchLayout(const Scene& scene, const EllipsoidCloud& cloud,
                                  CachedTexture& texture, const RenderSettings& settings,
                                  bool spotlight, bool targets_drawn);
  // Ellipsoids blended in the records' order, by their centres.
  void drawByCentre(const Batch& b, const std::vector<EllipsoidRecord>& ordered);
  // None when the lists would not fit in buffer textures.
  std::optional<BinLists> binLists(const std::vector<EllipsoidRecord>& ordered,
                                   const PassTarget& target, bool history) const;
  // The per-pixel pass: every hit of the batch composited front to back, at every pixel or
  // first at a sample rate (drawSampled, resolveSamples).
  void drawPerPixel(const Batch& b, const std::vector<EllipsoidRecord>& ordered,
                    const BinLists& bins);
  GLuint perPixelProgram(const Batch& b, const BinLists& bins, EllipsoidProgram which, int rate,
                         bool history_too = false);
  // Draws bins `rect` with `program` into a viewport of `size` whose pixel i stands at frame
  // pixel i * step: each pixel composites every hit of its bin, so disjoint rectangles give the
  // image one quad gives. Samples are drawn to the end of the last bin, past the frame's edge,
  // for the pixels next to it; `extra` more past the last bin (a continuous view's shifted
  // samples).
  void drawBinRect(GLuint program, glm::ivec2 size, int step, glm::ivec4 rect, int extra = 0);
  // Draws the batch's area with `draw(rect)`; false once cancelled.
  bool drawArea(const BinLists& bins, const std::function<void(glm::ivec4)>& draw);
  void drawSampled(const Batch& b, const BinLists& bins, int rate, bool reduced, double tolerance);
  void resolveSamples(const Batch& b, const BinLists& bins, int rate, glm::ivec2 size, bool reduced,
                      double tolerance);
  void drawRuns(const Batch& b, const BinLists& bins, EllipsoidProgram which, int rate,
                const std::vector<glm::ivec4>& runs);

  const GlApi& gl_;
  GlObject vertex_array_;  // empty: attribute-less draws
  struct FrameTexture {
    GlObject buffer, texture;
  };
  std::vector<FrameTexture> buffer_pool_;  // buffer textures, one per upload in a frame
  std::size_t next_buffer_ = 0;
  // Hit tests (the centre pass: fragments) drawn since the last glFinish, which llvmpipe may
  // not have run yet.
  std::int64_t queued_work_ = 0;
  GLsync part_fence_ = nullptr;  // the fence after the last part paceQueued saw queued
  GLint max_texels_ = 0;         // GL_MAX_TEXTURE_BUFFER_SIZE
  GlObject spotlight_;
  GlObject atlas_;
  GlObject atlas_framebuffer_;
  TileFormat atlas_format_ = TileFormat::kFloat;
  GlObject samples_, sample_distance_, samples_framebuffer_;
  glm::ivec2 samples_size_{0};
  std::map<std::string, GlObject> programs_;
  std::map<std::string, CachedTexture> textures_;
  std::map<std::string, BakedTable> tables_;
  std::uint64_t frame_ = 0;
  std::map<int, IndexedMesh> meshes_;
  std::map<std::size_t, Impostor> impostors_;  // by cloud index
  int impostor_renders_ = 0;
  // Continuous views' heap histories by view, in the order the frame draws its batches.
  std::map<std::string, std::vector<HeapHistory>> histories_;
  std::string continuous_view_;
  std::size_t next_history_ = 0;
  const std::atomic<bool>* cancel_ = nullptr;
  const SceneSunlight* sunlight_ = nullptr;
  std::function<void()> alive_;
  bool cancelled_ = false;
  FrameStats* stats_ = nullptr;    // the current frame's, borrowed from the GlRenderer
  GpuPassTimer* timer_ = nullptr;  // the GlRenderer's
};

}  // namespace nephele
