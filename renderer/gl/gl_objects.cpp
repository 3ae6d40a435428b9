#include "renderer/gl/gl_objects.h"

#include <atomic>
#include <cmath>
#include <vector>

namespace nephele {

void GlObject::reset() {
  if (!gl_ || name_ == 0) return;
  switch (kind_) {
    case Kind::kTexture:
      gl_->DeleteTextures(1, &name_);
      break;
    case Kind::kFramebuffer:
      gl_->DeleteFramebuffers(1, &name_);
      break;
    case Kind::kRenderbuffer:
      gl_->DeleteRenderbuffers(1, &name_);
      break;
    case Kind::kVertexArray:
      gl_->DeleteVertexArrays(1, &name_);
      break;
    case Kind::kProgram:
      gl_->DeleteProgram(name_);
      break;
    case Kind::kShader:
      gl_->DeleteShader(name_);
      break;
    case Kind::kBuffer:
      gl_->DeleteBuffers(1, &name_);
      break;
    case Kind::kQuery:
      gl_->DeleteQueries(1, &name_);
      break;
  }
  name_ = 0;
}

GlObject createTexture(const GlApi& gl, GLenum target) {
  GLuint name = 0;
  gl.CreateTextures(target, 1, &name);
  return {gl, GlObject::Kind::kTexture, name};
}

GlObject createTexture2D(const GlApi& gl, GLenum format, int width, int height) {
  GlObject texture = createTexture(gl, GL_TEXTURE_2D);
  const GLuint t = texture.get();
  gl.TextureStorage2D(t, 1, format, width, height);
  gl.TextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return texture;
}

GlObject createFramebuffer(const GlApi& gl) {
  GLuint name = 0;
  gl.CreateFramebuffers(1, &name);
  return {gl, GlObject::Kind::kFramebuffer, name};
}

GlObject createRenderbuffer(const GlApi& gl) {
  GLuint name = 0;
  gl.CreateRenderbuffers(1, &name);
  return {gl, GlObject::Kind::kRenderbuffer, name};
}

void clearGlErrors(const GlApi& gl) {
  while (gl.GetError() != GL_NO_ERROR) {
  }
}

bool framebufferUsable(const GlApi& gl, GLuint framebuffer) {
  return gl.CheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE &&
         gl.GetError() == GL_NO_ERROR;
}

GlObject createVertexArray(const GlApi& gl) {
  GLuint name = 0;
  gl.CreateVertexArrays(1, &name);
  return {gl, GlObject::Kind::kVertexArray, name};
}

GlObject createBuffer(const GlApi& gl) {
  GLuint name = 0;
  gl.CreateBuffers(1, &name);
  return {gl, GlObject::Kind::kBuffer, name};
}

IndexedMesh uploadMesh(const GlApi& gl, const std::vector<glm::vec3>& vertices,
                       const std::vector<GLuint>& indices) {
  IndexedMesh mesh;
  mesh.vertex_array = createVertexArray(gl);
  mesh.vertices = createBuffer(gl);
  mesh.indices = createBuffer(gl);
  gl.NamedBufferData(mesh.vertices.get(), GLsizeiptr(vertices.size() * sizeof(glm::vec3)),
                     vertices.data(), GL_STATIC_DRAW);
  gl.NamedBufferData(mesh.indices.get(), GLsizeiptr(indices.size() * sizeof(GLuint)),
                     indices.data(), GL_STATIC_DRAW);
  const GLuint vao = mesh.vertex_array.get();
  gl.VertexArrayVertexBuffer(vao, 0, mesh.vertices.get(), 0, sizeof(glm::vec3));
  gl.VertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  gl.VertexArrayAttribBinding(vao, 0, 0);
  gl.EnableVertexArrayAttrib(vao, 0);
  gl.VertexArrayElementBuffer(vao, mesh.indices.get());
  mesh.index_count = GLsizei(indices.size());
  return mesh;
}

void unitSphere(int slices, std::vector<glm::vec3>& vertices, std::vector<GLuint>& indices) {
  const double pi = 3.14159265358979323846;
  for (int j = 0; j <= slices; ++j) {
    const double theta = pi * j / slices;
    for (int i = 0; i <= slices; ++i) {
      const double phi = 2.0 * pi * i / slices;
      vertices.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta));
    }
  }
  for (int j = 0; j < slices; ++j)
    for (int i = 0; i < slices; ++i) {
      const GLuint a = j * (slices + 1) + i, b = a + 1, c = a + slices + 1, d = c + 1;
      indices.insert(indices.end(), {a, c, b, b, c, d});
    }
}

namespace {

GlObject compileShader(const GlApi& gl, GLenum stage, const std::string& source,
                       std::string& error) {
  GlObject shader(gl, GlObject::Kind::kShader, gl.CreateShader(stage));
  const char* text = source.c_str();
  gl.ShaderSource(shader.get(), 1, &text, nullptr);
  gl.CompileShader(shader.get());
  GLint ok = GL_FALSE;
  gl.GetShaderiv(shader.get(), GL_COMPILE_STATUS, &ok);
  if (ok) return shader;
  GLint length = 0;
  gl.GetShaderiv(shader.get(), GL_INFO_LOG_LENGTH, &length);
  std::vector<char> log(std::size_t(length) + 1, '\0');
  gl.GetShaderInfoLog(shader.get(), length, nullptr, log.data());
  error = std::string(stage == GL_VERTEX_SHADER ? "vertex" : "fragment") +
          " shader did not compile: " + log.data();
  return {};
}

}  // namespace

namespace {
std::atomic<std::uint64_t> programs_linked{0};
}  // namespace

std::uint64_t programsLinked() {
  return programs_linked.load(std::memory_order_relaxed);
}

GlObject createProgram(const GlApi& gl, const std::string& vertex_source,
                       const std::string& fragment_source, std::string& error) {
  programs_linked.fetch_add(1, std::memory_order_relaxed);
  GlObject vertex = compileShader(gl, GL_VERTEX_SHADER, vertex_source, error);
  if (!vertex) return {};
  GlObject fragment = compileShader(gl, GL_FRAGMENT_SHADER, fragment_source, error);
  if (!fragment) return {};
  GlObject program(gl, GlObject::Kind::kProgram, gl.CreateProgram());
  gl.AttachShader(program.get(), vertex.get());
  gl.AttachShader(program.get(), fragment.get());
  gl.LinkProgram(program.get());
  GLint ok = GL_FALSE;
  gl.GetProgramiv(program.get(), GL_LINK_STATUS, &ok);
  if (ok) return program;
  GLint length = 0;
  gl.GetProgramiv(program.get(), GL_INFO_LOG_LENGTH, &length);
  std::vector<char> log(std::size_t(length) + 1, '\0');
  gl.GetProgramInfoLog(program.get(), length, nullptr, log.data());
  error = std::string("program did not link: ") + log.data();
  return {};
}

}  // namespace nephele
