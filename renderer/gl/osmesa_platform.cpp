// OSMesa back end: Mesa's off-screen software context. GL_GLEXT_PROTOTYPES must precede
// osmesa.h (PLATFORM.md).
#define GL_GLEXT_PROTOTYPES
#include <GL/osmesa.h>

#include <array>

#include "renderer/gl/gl_platform.h"

namespace nephele {
namespace {

class OsmesaPlatform final : public GlPlatform {
 public:
  ~OsmesaPlatform() override {
    if (context_) OSMesaDestroyContext(context_);
  }
  std::string_view backendName() const override { return "osmesa"; }

  bool start(std::string& error) {
    const int attributes[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_PROFILE,
                              OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION,
                              4,
                              OSMESA_CONTEXT_MINOR_VERSION,
                              5,
                              0};
    context_ = OSMesaCreateContextAttribs(attributes, nullptr);
    if (!context_) {
      error = "osmesa: OSMesaCreateContextAttribs(4.5 core) failed";
      return false;
    }
    // OSMesa needs a colour buffer to be current; Nephele renders into FBOs, so 1x1 will do.
    if (!OSMesaMakeCurrent(context_, placeholder_.data(), GL_UNSIGNED_BYTE, 1, 1)) {
      error = "osmesa: OSMesaMakeCurrent failed";
      return false;
    }
    std::string load_error;
    if (!loadGlApi(
            gl_, [](const char* n) { return OSMesaGetProcAddress(n); }, load_error)) {
      error = "osmesa: " + load_error;
      return false;
    }
    return true;
  }

 private:
  OSMesaContext context_ = nullptr;
  std::array<unsigned char, 4> placeholder_{};
};

}  // namespace

std::unique_ptr<GlPlatform> createOsmesaPlatform(std::string& error) {
  auto platform = std::make_unique<OsmesaPlatform>();
  if (!platform->start(error)) return nullptr;
  return platform;
}

}  // namespace nephele
