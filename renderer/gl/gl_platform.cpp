#include "renderer/gl/gl_platform.h"

namespace nephele {

std::string GlPlatform::renderer() const {
  const auto* s = reinterpret_cast<const char*>(gl_.GetString(GL_RENDERER));
  return s ? s : "";
}

std::string GlPlatform::version() const {
  const auto* s = reinterpret_cast<const char*>(gl_.GetString(GL_VERSION));
  return s ? s : "";
}

std::unique_ptr<GlPlatform> createGlPlatform(GlBackend backend, std::string& error) {
  error.clear();
  std::string attempt_error;
  if (backend == GlBackend::kEgl || backend == GlBackend::kAuto) {
    if (auto platform = createEglPlatform(attempt_error)) return platform;
    error += attempt_error;
  }
  if (backend == GlBackend::kOsmesa || backend == GlBackend::kAuto) {
    if (auto platform = createOsmesaPlatform(attempt_error)) return platform;
    error += (error.empty() ? "" : "; ") + attempt_error;
  }
  error = "no OpenGL 4.5 core context could be created (tried: " + error + ")";
  return nullptr;
}

}  // namespace nephele
