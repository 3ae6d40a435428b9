#include "renderer/gl_objects.h"

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
  }
  name_ = 0;
}

GlObject createTexture(const GlApi& gl, GLenum target) {
  GLuint name = 0;
  gl.CreateTextures(target, 1, &name);
  return {gl, GlObject::Kind::kTexture, name};
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

GlObject createProgram(const GlApi& gl, const std::string& vertex_source,
                       const std::string& fragment_source, std::string& error) {
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
