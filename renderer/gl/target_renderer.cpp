#include "renderer/gl/target_renderer.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "renderer/gl/ellipsoid_shaders.h"
#include "renderer/gl/shaders/target_glsl.h"
#include "renderer/gl/sky_shaders.h"
#include "renderer/gl/view_uniforms.h"
#include "world/check.h"

namespace nephele {
namespace {

constexpr float kNear = 0.05f;  // metres
constexpr int kTargetSphereSlices = 64;
const char kBoxTag = 'b', kSphereTag = 's';  // their addresses key the shape meshes

using glsl::target::kFragment;  // shaders/target/shading.glsl, after the view chunk
using glsl::target::kVertex;    // shaders/target/mesh.vert

}  // namespace

TargetRenderer::TargetRenderer(const GlApi& gl) : gl_(gl) {}
TargetRenderer::~TargetRenderer() = default;

GLuint TargetRenderer::program() {
  if (program_) return program_.get();
  std::string error;
  // One program for every scene: targets are few, and their program holds every medium.
  program_ = createProgram(
      gl_, kVertex,
      "#version 450 core\n" + airDefines(kEveryAirMedium) + viewShaderSource() + kFragment, error);
  NEPHELE_CHECK(program_, "target program: " << error);
  return program_.get();
}

void TargetRenderer::prepare(int width, int height) {
  NEPHELE_CHECK(allocate(width, height),
                "target framebuffer " << width << "x" << height << " incomplete (reserve first)");
}

bool TargetRenderer::allocate(int width, int height) {
  if (framebuffer_ && width == width_ && height == height_) return true;
  width_ = height_ = 0;
  clearGlErrors(gl_);
  framebuffer_ = createFramebuffer(gl_);
  colour_ = createTexture(gl_, GL_TEXTURE_2D);
  distance_ = createTexture(gl_, GL_TEXTURE_2D);
  id_ = createTexture(gl_, GL_TEXTURE_2D);
  depth_ = createRenderbuffer(gl_);
  gl_.TextureStorage2D(colour_.get(), 1, GL_RGBA16F, width, height);
  gl_.TextureStorage2D(distance_.get(), 1, GL_R32F, width, height);
  gl_.TextureStorage2D(id_.get(), 1, GL_R32F, width, height);
  gl_.NamedRenderbufferStorage(depth_.get(), GL_DEPTH_COMPONENT32F, width, height);
  for (GLuint t : {colour_.get(), distance_.get(), id_.get()}) {
    gl_.TextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  const GLuint f = framebuffer_.get();
  gl_.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT0, colour_.get(), 0);
  gl_.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT1, distance_.get(), 0);
  gl_.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT2, id_.get(), 0);
  gl_.NamedFramebufferRenderbuffer(f, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.get());
  const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  gl_.NamedFramebufferDrawBuffers(f, 3, buffers);
  if (!framebufferUsable(gl_, f)) {
    for (GlObject* o : {&framebuffer_, &colour_, &distance_, &id_, &depth_}) *o = GlObject();
    return false;
  }
  width_ = width;
  height_ = height;
  return true;
}

const IndexedMesh& TargetRenderer::mesh(const Target& target) {
  const void* key = target.mesh.get();
  if (target.shape == TargetShape::kBox) key = &kBoxTag;
  if (target.shape == TargetShape::kEllipsoid) key = &kSphereTag;
  auto found = meshes_.find(key);
  if (found != meshes_.end()) return found->second;
  std::vector<glm::vec3> vertices;
  std::vector<GLuint> indices;
  if (target.shape == TargetShape::kBox) {
    for (int i = 0; i < 8; ++i)
      vertices.emplace_back(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    indices = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
               2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
  } else if (target.shape == TargetShape::kEllipsoid) {
    unitSphere(kTargetSphereSlices, vertices, indices);
  } else {
    for (const glm::dvec3& v : target.mesh->vertices) vertices.emplace_back(v);
    for (const auto& t : target.mesh->triangles) indices.insert(indices.end(), t.begin(), t.end());
  }
  return meshes_.emplace(key, uploadMesh(gl_, vertices, indices)).first->second;
}

bool TargetRenderer::draw(const Scene& scene, const SceneSunlight& sunlight) {
  if (scene.targets.empty()) return false;
  const Camera& camera = scene.camera;
  prepare(camera.width, camera.height);
  const GLuint f = framebuffer_.get();
  const float clear_colour[4] = {0, 0, 0, 0}, far_distance[4] = {1e30f, 0, 0, 0};
  const float nearest_depth = 0.0f;
  gl_.ClearNamedFramebufferfv(f, GL_COLOR, 0, clear_colour);
  gl_.ClearNamedFramebufferfv(f, GL_COLOR, 1, far_distance);
  gl_.ClearNamedFramebufferfv(f, GL_COLOR, 2, clear_colour);
  gl_.ClearNamedFramebufferfv(f, GL_DEPTH, 0, &nearest_depth);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, f);
  gl_.Viewport(0, 0, camera.width, camera.height);
  gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_GREATER);
  gl_.Disable(GL_BLEND);

  const GLuint p = program();
  gl_.UseProgram(p);
  setViewUniforms(gl_, p, camera, scene);
  const ViewBasis basis = viewBasis(camera);
  setUniform3(gl_, p, "u_clip_x", basis.right / (basis.tan_half_vfov * basis.aspect));
  setUniform3(gl_, p, "u_clip_y", basis.up / basis.tan_half_vfov);
  setUniform3(gl_, p, "u_clip_w", basis.forward);
  setUniform3(gl_, p, "u_to_sun", sunDirection(scene.sun));
  for (std::size_t t = 0; t < scene.targets.size(); ++t) {
    const Target& target = scene.targets[t];
    if (target.shape == TargetShape::kMesh && !target.mesh) continue;
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_id"), float(t + 1));
    const glm::dmat3 rotation = bodyToWorld(target.orientation);
    const glm::mat3 model(
        rotation * glm::dmat3(target.size.x, 0, 0, 0, target.size.y, 0, 0, 0, target.size.z));
    const glm::mat3 normal_matrix(rotation * glm::dmat3(1.0 / target.size.x, 0, 0, 0,
                                                        1.0 / target.size.y, 0, 0, 0,
                                                        1.0 / target.size.z));
    gl_.ProgramUniformMatrix3fv(p, gl_.GetUniformLocation(p, "u_model"), 1, GL_FALSE, &model[0][0]);
    gl_.ProgramUniformMatrix3fv(p, gl_.GetUniformLocation(p, "u_normal_matrix"), 1, GL_FALSE,
                                &normal_matrix[0][0]);
    setUniform3(gl_, p, "u_offset", target.centre - camera.position);
    setUniform3(gl_, p, "u_albedo", target.colour * scene.sun.colour);
    // A target is small beside a cloud's shadow: it takes the sunlight at its centre.
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_sunlight"),
                         float(sunlight.at(target.centre)));
    gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_smooth"),
                         target.shape == TargetShape::kEllipsoid ? 1 : 0);
    const IndexedMesh& m = mesh(target);
    gl_.BindVertexArray(m.vertex_array.get());
    gl_.DrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
  }
  gl_.Disable(GL_DEPTH_TEST);
  gl_.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  gl_.BindTextureUnit(kTargetColourUnit, colour_.get());
  gl_.BindTextureUnit(kTargetDistanceUnit, distance_.get());
  return true;
}

void TargetRenderer::read(std::vector<float>* distance, std::vector<float>* id) const {
  const GLsizei bytes = GLsizei(std::size_t(width_) * height_ * sizeof(float));
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  for (auto [plane, texture] : {std::pair{distance, distance_.get()}, std::pair{id, id_.get()}}) {
    if (!plane) continue;
    plane->resize(std::size_t(width_) * height_);
    gl_.GetTextureImage(texture, 0, GL_RED, GL_FLOAT, bytes, plane->data());
  }
}

}  // namespace nephele
