#pragma once
// The OpenGL 4.5 core entry points Nephele uses, loaded per context through the platform's
// own GetProcAddress. Nothing links libGL: with EGL and OSMesa in one process, a link-time
// glClear would bind every call to whichever library came first.
#include <GL/glcorearb.h>

namespace nephele {

// GL 1.1 entry points: glcorearb.h skips their typedefs when gl.h came first (osmesa.h).
using GlDeleteTexturesProc = void(APIENTRYP)(GLsizei n, const GLuint* textures);
using GlDrawArraysProc = void(APIENTRYP)(GLenum mode, GLint first, GLsizei count);
using GlDrawElementsProc = void(APIENTRYP)(GLenum mode, GLsizei count, GLenum type,
                                           const void* indices);
using GlColorMaskProc = void(APIENTRYP)(GLboolean r, GLboolean g, GLboolean b, GLboolean a);
using GlEnumProc = void(APIENTRYP)(GLenum value);  // glCullFace, glFrontFace, glDepthFunc
using GlScissorProc = void(APIENTRYP)(GLint x, GLint y, GLsizei width, GLsizei height);
using GlDepthMaskProc = void(APIENTRYP)(GLboolean flag);

#define NEPHELE_GL_FUNCTIONS(X)                                          \
  X(PFNGLGETSTRINGPROC, GetString)                                       \
  X(PFNGLGETERRORPROC, GetError)                                         \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                                   \
  X(PFNGLCREATESHADERPROC, CreateShader)                                 \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                                 \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                               \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                                   \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                         \
  X(PFNGLDELETESHADERPROC, DeleteShader)                                 \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                               \
  X(PFNGLATTACHSHADERPROC, AttachShader)                                 \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                                   \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                                 \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                       \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                               \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                                     \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                     \
  X(PFNGLPROGRAMUNIFORM1IPROC, ProgramUniform1i)                         \
  X(PFNGLPROGRAMUNIFORM2IPROC, ProgramUniform2i)                         \
  X(PFNGLPROGRAMUNIFORM1FPROC, ProgramUniform1f)                         \
  X(PFNGLPROGRAMUNIFORM1FVPROC, ProgramUniform1fv)                       \
  X(PFNGLPROGRAMUNIFORM2FVPROC, ProgramUniform2fv)                       \
  X(PFNGLPROGRAMUNIFORM3FVPROC, ProgramUniform3fv)                       \
  X(PFNGLPROGRAMUNIFORM4FVPROC, ProgramUniform4fv)                       \
  X(PFNGLCREATEVERTEXARRAYSPROC, CreateVertexArrays)                     \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                     \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                           \
  X(PFNGLCREATETEXTURESPROC, CreateTextures)                             \
  X(GlDeleteTexturesProc, DeleteTextures)                                \
  X(PFNGLTEXTURESTORAGE2DPROC, TextureStorage2D)                         \
  X(PFNGLTEXTURESUBIMAGE2DPROC, TextureSubImage2D)                       \
  X(PFNGLTEXTUREPARAMETERIPROC, TextureParameteri)                       \
  X(PFNGLGENERATETEXTUREMIPMAPPROC, GenerateTextureMipmap)               \
  X(PFNGLBINDTEXTUREUNITPROC, BindTextureUnit)                           \
  X(PFNGLTEXTUREBUFFERPROC, TextureBuffer)                               \
  X(PFNGLCREATERENDERBUFFERSPROC, CreateRenderbuffers)                   \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                   \
  X(PFNGLNAMEDRENDERBUFFERSTORAGEPROC, NamedRenderbufferStorage)         \
  X(PFNGLCREATEFRAMEBUFFERSPROC, CreateFramebuffers)                     \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                     \
  X(PFNGLNAMEDFRAMEBUFFERRENDERBUFFERPROC, NamedFramebufferRenderbuffer) \
  X(PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, CheckNamedFramebufferStatus)   \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                           \
  X(PFNGLVIEWPORTPROC, Viewport)                                         \
  X(PFNGLENABLEPROC, Enable)                                             \
  X(PFNGLDISABLEPROC, Disable)                                           \
  X(PFNGLENABLEIPROC, Enablei)                                           \
  X(PFNGLBLENDEQUATIONIPROC, BlendEquationi)                             \
  X(PFNGLDISABLEIPROC, Disablei)                                         \
  X(PFNGLBLENDFUNCSEPARATEPROC, BlendFuncSeparate)                       \
  X(GlDrawArraysProc, DrawArrays)                                        \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                                   \
  X(PFNGLREADPIXELSPROC, ReadPixels)                                     \
  X(PFNGLGETTEXTUREIMAGEPROC, GetTextureImage)                           \
  X(PFNGLFINISHPROC, Finish)                                             \
  X(PFNGLFENCESYNCPROC, FenceSync)                                       \
  X(PFNGLCLIENTWAITSYNCPROC, ClientWaitSync)                             \
  X(PFNGLDELETESYNCPROC, DeleteSync)                                     \
  X(GlDrawElementsProc, DrawElements)                                    \
  X(GlColorMaskProc, ColorMask)                                          \
  X(GlEnumProc, CullFace)                                                \
  X(GlEnumProc, FrontFace)                                               \
  X(GlEnumProc, DepthFunc)                                               \
  X(GlDepthMaskProc, DepthMask)                                          \
  X(GlScissorProc, Scissor)                                              \
  X(PFNGLTEXTURESTORAGE3DPROC, TextureStorage3D)                         \
  X(PFNGLTEXTURESUBIMAGE3DPROC, TextureSubImage3D)                       \
  X(PFNGLCLIPCONTROLPROC, ClipControl)                                   \
  X(PFNGLCLEARNAMEDFRAMEBUFFERFVPROC, ClearNamedFramebufferfv)           \
  X(PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, NamedFramebufferTexture)           \
  X(PFNGLNAMEDFRAMEBUFFERTEXTURELAYERPROC, NamedFramebufferTextureLayer) \
  X(PFNGLNAMEDFRAMEBUFFERDRAWBUFFERSPROC, NamedFramebufferDrawBuffers)   \
  X(PFNGLCREATEBUFFERSPROC, CreateBuffers)                               \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                               \
  X(PFNGLNAMEDBUFFERDATAPROC, NamedBufferData)                           \
  X(PFNGLNAMEDBUFFERSUBDATAPROC, NamedBufferSubData)                     \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                             \
  X(PFNGLVERTEXARRAYVERTEXBUFFERPROC, VertexArrayVertexBuffer)           \
  X(PFNGLVERTEXARRAYATTRIBFORMATPROC, VertexArrayAttribFormat)           \
  X(PFNGLVERTEXARRAYATTRIBBINDINGPROC, VertexArrayAttribBinding)         \
  X(PFNGLENABLEVERTEXARRAYATTRIBPROC, EnableVertexArrayAttrib)           \
  X(PFNGLVERTEXARRAYELEMENTBUFFERPROC, VertexArrayElementBuffer)         \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)                   \
  X(PFNGLBLENDEQUATIONSEPARATEPROC, BlendEquationSeparate)               \
  X(PFNGLCOPYIMAGESUBDATAPROC, CopyImageSubData)                         \
  X(PFNGLPROGRAMUNIFORMMATRIX3FVPROC, ProgramUniformMatrix3fv)           \
  X(PFNGLPROGRAMUNIFORMMATRIX4FVPROC, ProgramUniformMatrix4fv)           \
  X(PFNGLCREATEQUERIESPROC, CreateQueries)                               \
  X(PFNGLDELETEQUERIESPROC, DeleteQueries)                               \
  X(PFNGLBEGINQUERYPROC, BeginQuery)                                     \
  X(PFNGLENDQUERYPROC, EndQuery)                                         \
  X(PFNGLGETQUERYOBJECTUI64VPROC, GetQueryObjectui64v)

struct GlApi {
#define NEPHELE_GL_MEMBER(type, name) type name = nullptr;
  NEPHELE_GL_FUNCTIONS(NEPHELE_GL_MEMBER)
#undef NEPHELE_GL_MEMBER
};

}  // namespace nephele

#include <string>

namespace nephele {

// Fills `gl` from `lookup(name)`; on a missing entry point names it in `error`.
template <typename Lookup>
bool loadGlApi(GlApi& gl, Lookup lookup, std::string& error) {
#define NEPHELE_GL_LOAD(type, name)                      \
  gl.name = reinterpret_cast<type>(lookup("gl" #name));  \
  if (!gl.name) {                                        \
    error = "OpenGL entry point gl" #name " is missing"; \
    return false;                                        \
  }
  NEPHELE_GL_FUNCTIONS(NEPHELE_GL_LOAD)
#undef NEPHELE_GL_LOAD
  return true;
}

}  // namespace nephele
