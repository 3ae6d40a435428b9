// EGL back end: the device platform first (a GPU host renders on its GPU), then Mesa's
// surfaceless platform. Contexts are config-less and made current with no surface.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <string>
#include <vector>

#include "renderer/gl/gl_platform.h"

namespace nephele {
namespace {

std::string eglErrorText(const char* what) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "%s failed (EGL error 0x%04x)", what, eglGetError());
  return buffer;
}

class EglPlatform final : public GlPlatform {
 public:
  ~EglPlatform() override {
    if (display_ == EGL_NO_DISPLAY) return;
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    // The display stays initialised: it is a per-process singleton, and eglTerminate would
    // unload the driver only for the next platform to load it again.
  }
  std::string_view backendName() const override { return name_; }

  // Initialises `display`, creates a core 4.5 context and loads GL; false with `error` set.
  bool start(EGLDisplay display, std::string name, std::string& error) {
    display_ = display;
    name_ = std::move(name);
    if (display_ == EGL_NO_DISPLAY) return fail(error, eglErrorText("eglGetPlatformDisplayEXT"));
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display_, &major, &minor)) {
      display_ = EGL_NO_DISPLAY;
      return fail(error, eglErrorText("eglInitialize"));
    }
    if (!eglBindAPI(EGL_OPENGL_API)) return fail(error, eglErrorText("eglBindAPI(OpenGL)"));
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 4,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context_ == EGL_NO_CONTEXT) return fail(error, eglErrorText("eglCreateContext(4.5 core)"));
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      return fail(error, eglErrorText("eglMakeCurrent(no surface)"));
    std::string load_error;
    if (!loadGlApi(
            gl_, [](const char* n) { return eglGetProcAddress(n); }, load_error))
      return fail(error, load_error);
    return true;
  }

 private:
  bool fail(std::string& error, const std::string& why) {
    error = name_ + ": " + why;
    return false;
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  std::string name_;
};

}  // namespace

std::unique_ptr<GlPlatform> createEglPlatform(std::string& error) {
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_display) {
    error = "egl: eglGetPlatformDisplayEXT is not available";
    return nullptr;
  }
  std::string errors;
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  EGLint device_count = 0;
  std::vector<EGLDeviceEXT> devices(16);
  if (query_devices && query_devices(EGLint(devices.size()), devices.data(), &device_count)) {
    for (EGLint i = 0; i < device_count; ++i) {
      auto platform = std::make_unique<EglPlatform>();
      std::string attempt;
      if (platform->start(get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr), "egl-device",
                          attempt))
        return platform;
      errors += attempt + "; ";
    }
  } else {
    errors += "egl-device: no EGL devices; ";
  }
  auto platform = std::make_unique<EglPlatform>();
  std::string attempt;
  if (platform->start(get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                      "egl-surfaceless", attempt))
    return platform;
  error = errors + attempt;
  return nullptr;
}

}  // namespace nephele
