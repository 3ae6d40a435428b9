#include "renderer/gl/ellipsoid_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "renderer/gl/ellipsoid_internal.h"
#include "world/check.h"

// Elinas and Stuerzlinger's multipass ellipsoids: each ellipsoid drawn into a tile of an atlas from
// its own off-axis frustum, then the tiles composited back to front.
namespace nephele {

using namespace ellipsoid_detail;

namespace {

constexpr int kAtlasSize = 2048;
constexpr int kMaxTileSize = 1024;
constexpr double kTileNear = 1.0e-3;  // metres: the tile frusta's near plane

// The tile's off-axis frustum: clip coordinates of camera-relative points for the part
// `rect` of the camera's image, with the near plane at kTileNear.
glm::mat4 tileProjection(const ViewBasis& basis, glm::dvec4 rect) {
  const glm::dvec3 x = basis.right / (basis.tan_half_vfov * basis.aspect);
  const glm::dvec3 y = basis.up / basis.tan_half_vfov;
  const glm::dvec3 w = basis.forward;
  const glm::dvec3 tile_x = (2.0 * x - (rect.x + rect.z) * w) / (rect.z - rect.x);
  const glm::dvec3 tile_y = (2.0 * y - (rect.y + rect.w) * w) / (rect.w - rect.y);
  glm::dmat4 m(0.0);  // m[column][row]
  for (int c = 0; c < 3; ++c) {
    m[c][0] = tile_x[c];
    m[c][1] = tile_y[c];
    m[c][2] = w[c];
    m[c][3] = w[c];
  }
  m[3][2] = -2.0 * kTileNear;  // z = w - 2 near: clipped where w < near
  return glm::mat4(m);
}

// Slices for a silhouette within half a pixel of the true one: a polygon of n sides around
// a circle of r pixels strays by r (1 - cos(pi / n)).
int adaptiveSlices(double radius_px) {
  if (radius_px <= 1.0) return 8;
  const double n = std::numbers::pi / std::acos(std::max(1.0 - 0.5 / radius_px, -1.0));
  return std::clamp(4 * int(std::ceil(n / 4.0)), 8, 128);
}

}  // namespace

const IndexedMesh& EllipsoidRenderer::sphereMesh(int slices) {
  auto found = meshes_.find(slices);
  if (found != meshes_.end()) return found->second;
  std::vector<glm::vec3> vertices;
  std::vector<GLuint> indices;
  unitSphere(slices, vertices, indices);
  return meshes_.emplace(slices, uploadMesh(gl_, vertices, indices)).first->second;
}

void EllipsoidRenderer::prepareAtlas(TileFormat format) {
  if (atlas_ && atlas_format_ == format) return;
  createColourTarget(gl_, format == TileFormat::kFloat ? GL_RGBA16F : GL_RGBA8,
                     glm::ivec2(kAtlasSize), "atlas", atlas_, atlas_framebuffer_);
  atlas_format_ = format;
}

void EllipsoidRenderer::drawTiles(const Scene& scene, const EllipsoidCloud& cloud,
                                  CachedTexture& texture, const EllipsoidPassLayout& base,
                                  const RenderSettings& settings,
                                  std::vector<EllipsoidRecord>& records, const PassTarget& target,
                                  const AltitudeBand& band) {
  prepareAtlas(settings.tile_format);
  // Tile sizes: the screen rectangle rounded up to powers of two, or the fixed knob.
  std::vector<Tile> all;
  for (int i = 0; i < int(records.size()); ++i) {
    const glm::vec4 rect = records[i].v[10];
    const double w = 0.5 * (rect.z - rect.x) * target.width;
    const double h = 0.5 * (rect.w - rect.y) * target.height;
    Tile tile{i, settings.tile_resolution, settings.tile_resolution};
    if (settings.tile_resolution == 0)
      tile = {i, std::clamp(nextPowerOfTwo(w), 8, kMaxTileSize),
              std::clamp(nextPowerOfTwo(h), 8, kMaxTileSize)};
    all.push_back(tile);
  }
  // Batches in back-to-front order, each as many tiles as the atlas holds, packed first-fit
  // by decreasing size onto shelves.
  std::size_t next = 0;
  while (next < all.size()) {
    std::vector<Tile> batch;
    std::vector<Tile> trial;
    for (std::size_t i = next; i < all.size(); ++i) {
      trial.push_back(all[i]);
      std::vector<Tile> packed = trial;
      std::stable_sort(packed.begin(), packed.end(), [](const Tile& a, const Tile& b) {
        return a.height != b.height ? a.height > b.height : a.width > b.width;
      });
      int x = 0, y = 0, shelf = 0;
      bool fits = true;
      for (Tile& t : packed) {
        if (x + t.width > kAtlasSize) x = 0, y += shelf, shelf = 0;
        if (y + t.height > kAtlasSize) {
          fits = false;
          break;
        }
        t.x = x, t.y = y;
        x += t.width;
        shelf = std::max(shelf, t.height);
      }
      if (!fits) break;
      batch = packed;
    }
    NEPHELE_CHECK(!batch.empty(), "tile larger than the atlas");
    next += batch.size();
    renderAtlasBatch(scene, cloud, texture, base, settings, records, batch, target, band);
  }
}

void EllipsoidRenderer::renderAtlasBatch(const Scene& scene, const EllipsoidCloud& cloud,
                                         const CachedTexture& texture,
                                         const EllipsoidPassLayout& base,
                                         const RenderSettings& settings,
                                         std::vector<EllipsoidRecord>& records,
                                         std::vector<Tile>& tiles, const PassTarget& target,
                                         const AltitudeBand& band) {
  for (const Tile& t : tiles) records[t.record].v[15] = glm::vec4(t.x, t.y, t.width, t.height);
  uploadRecords(records);
  const ViewBasis basis = viewBasis(scene.camera);

  // The tile passes, into the atlas.
  gl_.BindFramebuffer(GL_FRAMEBUFFER, atlas_framebuffer_.get());
  gl_.Enable(GL_SCISSOR_TEST);
  const float zero[4] = {0, 0, 0, 0};
  for (const Tile& t : tiles) {
    gl_.Scissor(t.x, t.y, t.width, t.height);
    gl_.ClearNamedFramebufferfv(atlas_framebuffer_.get(), GL_COLOR, 0, zero);
  }
  gl_.Disable(GL_SCISSOR_TEST);
  gl_.Enable(GL_CULL_FACE);
  gl_.CullFace(GL_BACK);
  gl_.FrontFace(GL_CCW);
  for (EllipsoidProgram pass : {EllipsoidProgram::kTileThreshold, EllipsoidProgram::kTileLimb,
                                EllipsoidProgram::kTileColour}) {
    EllipsoidPassLayout layout = base;
    layout.program = pass;
    layout.targets = false;  // tiles are not in screen space; the composite tests targets
    const GLuint p = program(layout);
    gl_.UseProgram(p);
    setCloudUniforms(p, scene, cloud, texture, layout.texture, band);
    if (pass == EllipsoidProgram::kTileThreshold) {
      gl_.Disable(GL_BLEND);
    } else if (pass == EllipsoidProgram::kTileLimb) {
      // alpha -= (T2 - T1)(1 - g): reverse subtraction, alpha only.
      gl_.Enable(GL_BLEND);
      gl_.BlendEquationSeparate(GL_FUNC_ADD, GL_FUNC_REVERSE_SUBTRACT);
      gl_.BlendFuncSeparate(GL_ONE, GL_ONE, GL_ONE, GL_ONE);
      gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_TRUE);
    } else {
      gl_.Disable(GL_BLEND);
      gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
    }
    for (const Tile& t : tiles) {
      const EllipsoidRecord& r = records[t.record];
      gl_.Viewport(t.x, t.y, t.width, t.height);
      const glm::mat4 projection = tileProjection(basis, glm::dvec4(r.v[10]));
      gl_.ProgramUniformMatrix4fv(p, gl_.GetUniformLocation(p, "u_projection"), 1, GL_FALSE,
                                  &projection[0][0]);
      gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_index"), t.record);
      const double radius_px = 0.25 * std::max((r.v[10].z - r.v[10].x) * target.width,
                                               (r.v[10].w - r.v[10].y) * target.height);
      const IndexedMesh& mesh =
          sphereMesh(settings.tessellation > 0 ? settings.tessellation : adaptiveSlices(radius_px));
      gl_.BindVertexArray(mesh.vertex_array.get());
      gl_.DrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr);
      ++stats_->atlas_passes;
    }
  }
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.BlendEquationSeparate(GL_FUNC_ADD, GL_FUNC_ADD);
  gl_.Disable(GL_CULL_FACE);
  compositeAtlasTiles(scene, cloud, texture, base, records, tiles, target, band);
}

void EllipsoidRenderer::compositeAtlasTiles(const Scene& scene, const EllipsoidCloud& cloud,
                                            const CachedTexture& texture,
                                            const EllipsoidPassLayout& base,
                                            const std::vector<EllipsoidRecord>& records,
                                            const std::vector<Tile>& tiles,
                                            const PassTarget& target, const AltitudeBand& band) {
  // Every tile as a screen rectangle, back to front (records are in that order).
  gl_.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  gl_.Viewport(0, 0, target.width, target.height);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  EllipsoidPassLayout layout = base;
  layout.program = EllipsoidProgram::kTileComposite;
  const GLuint p = program(layout);
  gl_.UseProgram(p);
  setCloudUniforms(p, scene, cloud, texture, layout.texture, band);
  const glm::vec2 atlas_size(kAtlasSize, kAtlasSize);
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_atlas_size"), 1, &atlas_size.x);
  gl_.BindTextureUnit(kAtlasTextureUnit, atlas_.get());
  gl_.BindVertexArray(vertex_array_.get());
  std::vector<int> order;
  for (const Tile& t : tiles) order.push_back(t.record);
  std::sort(order.begin(), order.end());
  for (int i : order) {
    const glm::vec4 rect = records[i].v[10];
    const glm::vec2 polygon[4] = {
        {rect.x, rect.y}, {rect.z, rect.y}, {rect.z, rect.w}, {rect.x, rect.w}};
    gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), 4, &polygon[0].x);
    gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_index"), i);
    gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 4);
    ++stats_->ellipsoid_passes;
  }
}

}  // namespace nephele
