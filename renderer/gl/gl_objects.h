#pragma once
// RAII ownership of GL object names. Every object borrows the GlApi of the context that made
// it; the context must outlive its objects.
#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/gl/gl_api.h"

namespace nephele {

class GlObject {
 public:
  enum class Kind {
    kTexture,
    kFramebuffer,
    kRenderbuffer,
    kVertexArray,
    kProgram,
    kShader,
    kBuffer,
    kQuery
  };

  GlObject() = default;
  GlObject(const GlApi& gl, Kind kind, GLuint name) : gl_(&gl), kind_(kind), name_(name) {}
  GlObject(GlObject&& other) noexcept { *this = std::move(other); }
  GlObject& operator=(GlObject&& other) noexcept {
    if (this != &other) {
      reset();
      gl_ = std::exchange(other.gl_, nullptr);
      kind_ = other.kind_;
      name_ = std::exchange(other.name_, 0);
    }
    return *this;
  }
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;
  ~GlObject() { reset(); }

  GLuint get() const { return name_; }
  explicit operator bool() const { return name_ != 0; }
  void reset();

 private:
  const GlApi* gl_ = nullptr;
  Kind kind_ = Kind::kTexture;
  GLuint name_ = 0;
};

GlObject createTexture(const GlApi& gl, GLenum target);
GlObject createFramebuffer(const GlApi& gl);
GlObject createRenderbuffer(const GlApi& gl);
GlObject createVertexArray(const GlApi& gl);
GlObject createBuffer(const GlApi& gl);
// A 2D texture of one level and this format, read bilinearly and clamped to its edges.
GlObject createTexture2D(const GlApi& gl, GLenum format, int width, int height);

// Allocating render targets: clear GL's error flags first, then, once the storage is made and
// attached, ask whether the framebuffer is usable: complete, and no GL error since (a failed
// allocation may leave a framebuffer complete and flag GL_OUT_OF_MEMORY).
void clearGlErrors(const GlApi& gl);
bool framebufferUsable(const GlApi& gl, GLuint framebuffer);

// A triangle mesh on the GPU: positions (attribute 0, vec3) and 32-bit indices.
struct IndexedMesh {
  GlObject vertex_array, vertices, indices;
  GLsizei index_count = 0;
};
IndexedMesh uploadMesh(const GlApi& gl, const std::vector<glm::vec3>& vertices,
                       const std::vector<GLuint>& indices);

// The unit sphere, `slices` around and `slices` from pole to pole, counter-clockwise seen
// from outside.
void unitSphere(int slices, std::vector<glm::vec3>& vertices, std::vector<GLuint>& indices);

// Drops the least recently used entries of `cache` (a map whose values carry `last_frame`)
// until at most `keep` remain, but never one used in `frame`: the baked tables a renderer
// keeps for the frames that come back to them.
template <typename Map>
void keepMostRecent(Map& cache, std::size_t keep, std::uint64_t frame) {
  while (cache.size() > keep) {
    auto oldest = std::min_element(cache.begin(), cache.end(), [](const auto& a, const auto& b) {
      return a.second.last_frame < b.second.last_frame;
    });
    if (oldest->second.last_frame == frame) break;  // all used in this frame
    cache.erase(oldest);
  }
}

// Compiles and links a vertex + fragment program. On failure returns an empty object and
// puts the driver's log in `error`.
GlObject createProgram(const GlApi& gl, const std::string& vertex_source,
                       const std::string& fragment_source, std::string& error);
// Programs createProgram has linked in this process (FrameStats::programs_compiled).
std::uint64_t programsLinked();

}  // namespace nephele
