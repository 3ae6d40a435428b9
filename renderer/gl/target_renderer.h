#pragma once
// Opaque targets (Elinas section 4.3): drawn first with a depth buffer into their own colour
// and distance textures, which every later pass reads per pixel, so clouds hide targets and
// targets hide clouds pixel by pixel.
#include <map>
#include <vector>

#include "renderer/gl/gl_objects.h"
#include "world/formations/cloud_shadow.h"
#include "world/scene.h"

namespace nephele {

class TargetRenderer {
 public:
  explicit TargetRenderer(const GlApi& gl);
  ~TargetRenderer();

  // Draws the scene's targets and binds their colour (fogged, lit) and distance along the
  // unit view ray (1e30 where none) to the view chunk's texture units, each lit with the
  // `sunlight` at its centre. A scene without targets draws nothing and returns false.
  bool draw(const Scene& scene, const SceneSunlight& sunlight = {});
  // After draw: the distance along each pixel's unit view ray to the nearest target (1e30 where
  // none) and 1 + that target's index (0 where none), rows bottom-up as GL stores them.
  void read(std::vector<float>* distance, std::vector<float>* id) const;
  // Allocates the width x height targets draw() uses; false when this GL cannot.
  bool allocate(int width, int height);

 private:
  void prepare(int width, int height);
  const IndexedMesh& mesh(const Target& target);
  GLuint program();

  const GlApi& gl_;
  GlObject framebuffer_, colour_, distance_, id_, depth_;
  int width_ = 0, height_ = 0;
  GlObject program_;
  std::map<const void*, IndexedMesh> meshes_;  // by shape tag or TriangleMesh
};

}  // namespace nephele
