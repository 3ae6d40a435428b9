#pragma once
// Automaton clouds on the GL: each cloud's two keyframes (density and sunlight on the
// lattice) live in one 3D texture, uploaded only when the World makes new keyframes; a
// fragment pass over the cloud's screen rectangle marches the view ray through it with the
// exact exponential per step and writes premultiplied colour and coverage for "over".
#include <map>
#include <memory>
#include <string>

#include "renderer/frame_stats.h"
#include "renderer/gl/gl_objects.h"
#include "renderer/gl/view_uniforms.h"
#include "renderer/render_settings.h"
#include "world/scene.h"

namespace nephele {

class AutomatonRenderer {
 public:
  explicit AutomatonRenderer(const GlApi& gl);

  // Starts a frame whose passes and uploads are counted into `stats`.
  void beginFrame(FrameStats& stats);
  // Draws scene.automata[index] over what the framebuffer holds (blending set here).
  // Only the rays whose entry into the volume lies in `band` (a layer cutting the cloud).
  void drawCloud(const Scene& scene, std::size_t index, const RenderSettings& settings,
                 bool targets_drawn, const AltitudeBand& band);
  // Releases the textures of clouds this frame did not draw.
  void endFrame();

  // Volume uploads since construction (each keyframe change costs one).
  int uploads() const { return uploads_; }

 private:
  struct Volume {
    std::shared_ptr<const AutomatonKeyframe> from, to;  // kept alive: compared by identity
    GlObject texture;                                   // density and sunlight of both keyframes
    GlObject sky;                                       // skylight of both keyframes
    bool used = false;
  };

  GLuint program(unsigned air, bool targets, PhaseFunction phase);
  Volume& volume(const Scene& scene, std::size_t index);

  const GlApi& gl_;
  GlObject vertex_array_;
  std::map<std::string, GlObject> programs_;
  std::map<std::string, Volume> volumes_;  // by cloud index and name
  int uploads_ = 0;
  FrameStats* stats_ = nullptr;  // the current frame's, borrowed from the GlRenderer
};

}  // namespace nephele
