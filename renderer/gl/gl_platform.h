#pragma once
// Headless OpenGL contexts behind one interface (EGL or OSMesa).
#include <memory>
#include <string>
#include <string_view>

#include "renderer/gl/gl_api.h"

namespace nephele {

enum class GlBackend { kAuto, kEgl, kOsmesa };

// A current OpenGL 4.5 core context with no window; rendering goes into framebuffer objects.
class GlPlatform {
 public:
  virtual ~GlPlatform() = default;
  virtual std::string_view backendName() const = 0;  // "egl-device", "egl-surfaceless", "osmesa"
  const GlApi& gl() const { return gl_; }
  std::string renderer() const;  // GL_RENDERER
  std::string version() const;   // GL_VERSION

 protected:
  GlApi gl_;
};

// Creates a context: kAuto tries EGL (device platform, so a GPU host renders on its GPU, then
// surfaceless Mesa) and then OSMesa. On failure returns null and sets `error` to what was
// tried and why each attempt failed.
std::unique_ptr<GlPlatform> createGlPlatform(GlBackend backend, std::string& error);

std::unique_ptr<GlPlatform> createEglPlatform(std::string& error);
std::unique_ptr<GlPlatform> createOsmesaPlatform(std::string& error);

}  // namespace nephele
