#pragma once
// What one frame did, so that a user can see that a scene pays only for what it shows
// (`nephele render --stats`, the daemon's `stats`). The GL back end fills it; the CPU
// reference leaves it at zero (Renderer::lastFrameStats).
#include <array>
#include <chrono>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace nephele {

// Where a frame's time goes (docs/ACCURACY.md, "Frame budget"): the CPU's stages before and
// between the passes, the GPU's passes by kind (GL timer queries), and the readback. One table
// of names serves the log line, the daemon's stats and /metrics, and the benchmarks.
enum class CpuStage : std::size_t {
  kScene,    // the rest: the draw list (layers banded, clouds culled and ordered) and the
             // passes' own GL calls
  kHeaps,    // heaps of the cloud fields generated around the camera (withFieldClouds)
  kBudget,   // the frame's work budget (withinEllipsoidBudget)
  kRecords,  // ellipsoid records, heap envelopes, the per-pixel pass's screen bins
  kUploads,  // tables baked, clipmap strips evaluated, buffer textures and volumes sent
  kShadows,  // the lobes that shadow the ground gathered, with their mean-opacity tables
  kCount
};
inline constexpr std::array<const char*, std::size_t(CpuStage::kCount)> kCpuStageNames{
    "scene", "heaps", "budget", "records", "uploads", "shadows"};

enum class GpuPass : std::size_t {
  kTargets,   // opaque target meshes
  kClipmaps,  // layer texels evaluated into clipmaps
  kSky,       // background and layers
  kHeaps,     // ellipsoid clouds: fused, per-pixel, samples, tiles, impostors
  kAutomata,  // volume marches
  kVeil,      // the in-cloud veil
  kReuse,     // a continuous view's last frame reprojected and merged with this frame's samples
  kShadows,   // the ground's shadow map (drawn when its casters or the sun changed)
  kCount
};
inline constexpr std::array<const char*, std::size_t(GpuPass::kCount)> kGpuPassNames{
    "targets", "clipmaps", "sky", "heaps", "automata", "veil", "reuse", "shadows"};

struct FrameTimes {
  std::array<double, std::size_t(CpuStage::kCount)> cpu_ms{};
  // GL_TIME_ELAPSED per kind of pass, summed over the frame; 0 where the GL has no timer.
  std::array<double, std::size_t(GpuPass::kCount)> gpu_ms{};
  double submit_ms = 0.0;    // the CPU's whole part, from the scene to the last pass queued
  double wait_ms = 0.0;      // then until the GPU has finished the passes (glFinish)
  double readback_ms = 0.0;  // glReadPixels and the conversion to the frame's layout
  double encode_ms = 0.0;    // PNG, JPEG, EXR or raw packing; set by whoever encodes

  double& cpu(CpuStage s) { return cpu_ms[std::size_t(s)]; }
  double& gpu(GpuPass p) { return gpu_ms[std::size_t(p)]; }
  double cpu(CpuStage s) const { return cpu_ms[std::size_t(s)]; }
  double gpu(GpuPass p) const { return gpu_ms[std::size_t(p)]; }
  double gpuTotal() const;
  // Adds `weight` times every figure of `other` (a mean over frames: weight 1 / frames).
  void accumulate(const FrameTimes& other, double weight = 1.0);
  // Every figure in milliseconds with its name: cpu_<stage>, gpu_<pass>, submit, wait,
  // readback, encode.
  std::vector<std::pair<std::string, double>> fields() const;
};

// Adds the scope's wall-clock time, in milliseconds, to `total` (a CPU stage of FrameTimes).
class StageClock {
 public:
  explicit StageClock(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~StageClock() {
    total_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
                  .count();
  }
  StageClock(const StageClock&) = delete;
  StageClock& operator=(const StageClock&) = delete;

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

struct FrameStats {
  int sky_passes = 0;        // background and layer passes
  int ellipsoid_passes = 0;  // fused draws, tile composites and impostor billboards
  int atlas_passes = 0;      // multipass: tile passes into the atlas (Elinas)
  int automaton_passes = 0;  // volume marches
  int target_passes = 0;     // opaque target meshes
  int veil_passes = 0;       // the in-cloud veil
  int shadow_maps = 0;       // the ground's shadow map drawn anew (MODEL.md section 16)
  // Per-pixel ellipsoid passes drawn from samples behind a thick veil (MODEL.md section 15)
  int sampled_passes = 0;
  // Of those, a continuous view's heaps resolved with its last frame (MODEL.md section 15,
  // "reuse across frames")
  int reused_passes = 0;
  int ellipsoids_drawn = 0;    // in view and drawn (directly or into an impostor)
  int ellipsoids_culled = 0;   // behind the eye, off screen, or with the eye inside
  int impostors_drawn = 0;     // far clouds drawn from an impostor
  int impostors_rendered = 0;  // impostors (re)rendered this frame
  // Gardner terms a pixel of the layers evaluates at most, summed over the layers drawn: the
  // term filter (MODEL.md section 2) drops terms above half the sampling frequency, at the
  // finest footprint a layer can show (straight above or below the camera).
  int layer_terms = 0;
  int layer_terms_total = 0;  // the layers' terms before the filter
  int volume_uploads = 0;     // automaton keyframe volumes sent to the GPU
  // Layer texels evaluated into clipmaps (MODEL.md section 2): every ring when a clipmap is
  // new, then only the strips the camera uncovers.
  int layer_texels_baked = 0;
  // Shader programs compiled for this frame: those of a pass first drawn. A daemon that
  // prewarmed ([world] prewarm) compiles none at a weather change.
  int programs_compiled = 0;
  FrameTimes times;

  int passes() const {
    return sky_passes + ellipsoid_passes + atlas_passes + automaton_passes + target_passes +
           veil_passes;
  }
  // Every figure with its name, `passes` first: one list for the log line and the daemon.
  std::vector<std::pair<const char*, int>> fields() const;
  // One line of key=value pairs, the times in milliseconds after the counts.
  std::string line() const;
};

}  // namespace nephele
