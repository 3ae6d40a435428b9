#pragma once
// The ground's cloud shadows on the GL (MODEL.md section 16): the share of the sunlight that
// reaches each point of the ground, as world/formations/cloud_shadow.h computes it, held in a
// square map over the ground where the casters' shadows fall. Every caster is one instanced
// quad over its footprint whose fragments multiply the map by casterSunlight, so the product
// needs no order. The map is drawn again only when its casters, their tables or the sun change:
// the views of one eye at one tick share it.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/frame_stats.h"
#include "renderer/gl/gl_objects.h"
#include "renderer/gl/gpu_pass_timer.h"
#include "world/formations/cloud_shadow.h"

namespace nephele {

class ShadowMap {
 public:
  explicit ShadowMap(const GlApi& gl);

  // Makes the map of `shadows` at `size` texels a side (0: none), at most 2 shadowRange
  // metres a side about the camera's ground point, unless the one held serves: the same casters
  // from their anchor (the first one's centre), tables, sun and region. Leaves the GL's
  // framebuffer, viewport and vertex array to the caller.
  void prepare(const CloudShadows& shadows, glm::dvec3 camera, int size, FrameStats& stats,
               GpuPassTimer& timer);
  bool active() const { return active_; }
  // Binds the map to texture `unit` and sets the sky pass's uniforms u_shadow_map,
  // u_shadow_centre (the map's centre from the camera, metres), u_shadow_half (its half side)
  // and u_shadow_floor (the casters' lowest point above the camera, CloudShadows::floor).
  void bind(GLuint program, GLuint unit, glm::dvec3 camera) const;
  int draws() const { return draws_; }  // maps drawn since construction
  // The map's stages: the shared formulas, then footprint_vertex.glsl; the table size, the
  // formulas, then sunlight.glsl.
  static std::string vertexSource();
  static std::string fragmentSource();

 private:
  // Uploads the casters' records and tables and draws the map.
  void draw(const CloudShadows& shadows, const std::vector<glm::vec4>& records,
            const std::vector<float>& tables, glm::vec3 to_sun, int size, double half,
            FrameStats& stats, GpuPassTimer& timer);

  const GlApi& gl_;
  GlObject program_, vertex_array_, framebuffer_, texture_, tables_, records_buffer_, records_;
  int size_ = 0;
  bool active_ = false;
  glm::dvec2 centre_{0.0};
  double half_ = 0.0;
  double floor_ = 0.0;
  std::uint64_t key_ = 0;
  int draws_ = 0;
};

}  // namespace nephele
