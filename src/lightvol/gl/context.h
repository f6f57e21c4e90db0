// Headless OpenGL 4.5 core through EGL, with no display and no window (docs/design.md §7).
//
// On a machine without a GPU this runs on Mesa's llvmpipe. Everything a renderer needs fits in a
// few calls:
//
//   Result<std::unique_ptr<gl::Context>> ctx = gl::Context::create();   // current on this thread
//   Result<gl::Program> prog = gl::Program::compile(vertex_src, fragment_src, "volume");
//   Result<gl::Framebuffer> fbo = gl::Framebuffer::create(w, h, {GL_R32F}, /*depth=*/false);
//   fbo->bind();  ...draw with the gl* functions below...
//   std::vector<float> pixels = fbo->read(0, 1);                       // first stored row = top
//
// OpenGL functions are loaded through eglGetProcAddress into pointers declared in this namespace
// under their usual names (`lightvol::gl::glDrawArrays`), so code inside `namespace lightvol::gl`
// or with `using namespace lightvol::gl` calls them as usual. An engine with a context of its own
// (GLFW, SDL, its own EGL or GLX) loads them through its loader instead: load_functions below. Do
// not also include <GL/gl.h>: it declares the same names globally. Constants (GL_R32F, ...) and
// types come from <GL/glcorearb.h>.
//
// Threading: a Context is current on the thread that created it; all GL objects below must be
// created, used and destroyed on that thread while the Context lives.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <GL/glcorearb.h>

#include <lightvol/core/result.h>

namespace lightvol::gl {

// X-macro list of the OpenGL entry points lightvol uses. Add a line to use another one.
#define LIGHTVOL_GL_FUNCTIONS(X)                                     \
  X(PFNGLGETSTRINGPROC, glGetString)                                 \
  X(PFNGLGETTEXIMAGEPROC, glGetTexImage)                             \
  X(PFNGLGETERRORPROC, glGetError)                                   \
  X(PFNGLGETINTEGERVPROC, glGetIntegerv)                             \
  X(PFNGLVIEWPORTPROC, glViewport)                                   \
  X(PFNGLCLEARCOLORPROC, glClearColor)                               \
  X(PFNGLCLEARDEPTHPROC, glClearDepth)                               \
  X(PFNGLCLEARPROC, glClear)                                         \
  X(PFNGLENABLEPROC, glEnable)                                       \
  X(PFNGLDISABLEPROC, glDisable)                                     \
  X(PFNGLBLENDFUNCPROC, glBlendFunc)                                 \
  X(PFNGLBLENDEQUATIONPROC, glBlendEquation)                         \
  X(PFNGLDEPTHFUNCPROC, glDepthFunc)                                 \
  X(PFNGLDEPTHMASKPROC, glDepthMask)                                 \
  X(PFNGLCULLFACEPROC, glCullFace)                                   \
  X(PFNGLFRONTFACEPROC, glFrontFace)                                 \
  X(PFNGLCOLORMASKPROC, glColorMask)                                 \
  X(PFNGLPOLYGONOFFSETPROC, glPolygonOffset)                         \
  X(PFNGLDRAWARRAYSPROC, glDrawArrays)                               \
  X(PFNGLDRAWELEMENTSPROC, glDrawElements)                           \
  X(PFNGLFINISHPROC, glFinish)                                       \
  X(PFNGLFLUSHPROC, glFlush)                                         \
  X(PFNGLREADBUFFERPROC, glReadBuffer)                               \
  X(PFNGLREADPIXELSPROC, glReadPixels)                               \
  X(PFNGLPIXELSTOREIPROC, glPixelStorei)                             \
  X(PFNGLCREATESHADERPROC, glCreateShader)                           \
  X(PFNGLSHADERSOURCEPROC, glShaderSource)                           \
  X(PFNGLCOMPILESHADERPROC, glCompileShader)                         \
  X(PFNGLGETSHADERIVPROC, glGetShaderiv)                             \
  X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)                   \
  X(PFNGLDELETESHADERPROC, glDeleteShader)                           \
  X(PFNGLCREATEPROGRAMPROC, glCreateProgram)                         \
  X(PFNGLATTACHSHADERPROC, glAttachShader)                           \
  X(PFNGLLINKPROGRAMPROC, glLinkProgram)                             \
  X(PFNGLGETPROGRAMIVPROC, glGetProgramiv)                           \
  X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)                 \
  X(PFNGLDELETEPROGRAMPROC, glDeleteProgram)                         \
  X(PFNGLUSEPROGRAMPROC, glUseProgram)                               \
  X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)               \
  X(PFNGLUNIFORM1IPROC, glUniform1i)                                 \
  X(PFNGLUNIFORM1FPROC, glUniform1f)                                 \
  X(PFNGLUNIFORM2FPROC, glUniform2f)                                 \
  X(PFNGLUNIFORM2IPROC, glUniform2i)                                 \
  X(PFNGLUNIFORM3FPROC, glUniform3f)                                 \
  X(PFNGLUNIFORM4FPROC, glUniform4f)                                 \
  X(PFNGLUNIFORM1FVPROC, glUniform1fv)                               \
  X(PFNGLUNIFORMMATRIX3FVPROC, glUniformMatrix3fv)                   \
  X(PFNGLUNIFORMMATRIX4FVPROC, glUniformMatrix4fv)                   \
  X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays)                     \
  X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)                     \
  X(PFNGLDELETEVERTEXARRAYSPROC, glDeleteVertexArrays)               \
  X(PFNGLGENBUFFERSPROC, glGenBuffers)                               \
  X(PFNGLBINDBUFFERPROC, glBindBuffer)                               \
  X(PFNGLBUFFERDATAPROC, glBufferData)                               \
  X(PFNGLDELETEBUFFERSPROC, glDeleteBuffers)                         \
  X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)             \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)     \
  X(PFNGLGENTEXTURESPROC, glGenTextures)                             \
  X(PFNGLBINDTEXTUREPROC, glBindTexture)                             \
  X(PFNGLACTIVETEXTUREPROC, glActiveTexture)                         \
  X(PFNGLTEXIMAGE2DPROC, glTexImage2D)                               \
  X(PFNGLTEXIMAGE3DPROC, glTexImage3D)                               \
  X(PFNGLTEXSUBIMAGE2DPROC, glTexSubImage2D)                         \
  X(PFNGLTEXPARAMETERIPROC, glTexParameteri)                         \
  X(PFNGLDELETETEXTURESPROC, glDeleteTextures)                       \
  X(PFNGLGENFRAMEBUFFERSPROC, glGenFramebuffers)                     \
  X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)                     \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, glFramebufferTexture2D)           \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, glCheckFramebufferStatus)       \
  X(PFNGLDELETEFRAMEBUFFERSPROC, glDeleteFramebuffers)               \
  X(PFNGLDRAWBUFFERSPROC, glDrawBuffers)                             \
  X(PFNGLGENQUERIESPROC, glGenQueries)                               \
  X(PFNGLDELETEQUERIESPROC, glDeleteQueries)                         \
  X(PFNGLBEGINQUERYPROC, glBeginQuery)                               \
  X(PFNGLENDQUERYPROC, glEndQuery)                                   \
  X(PFNGLGETQUERYOBJECTUI64VPROC, glGetQueryObjectui64v)             \
  X(PFNGLGETTEXLEVELPARAMETERIVPROC, glGetTexLevelParameteriv)       \
  X(PFNGLGETTEXPARAMETERIVPROC, glGetTexParameteriv)                 \
  X(PFNGLISTEXTUREPROC, glIsTexture)                                 \
  X(PFNGLBINDBUFFERBASEPROC, glBindBufferBase)                       \
  X(PFNGLGETBUFFERSUBDATAPROC, glGetBufferSubData)                   \
  X(PFNGLTRANSFORMFEEDBACKVARYINGSPROC, glTransformFeedbackVaryings) \
  X(PFNGLBEGINTRANSFORMFEEDBACKPROC, glBeginTransformFeedback)       \
  X(PFNGLENDTRANSFORMFEEDBACKPROC, glEndTransformFeedback)           \
  X(PFNGLDISPATCHCOMPUTEPROC, glDispatchCompute)                     \
  X(PFNGLDISPATCHCOMPUTEINDIRECTPROC, glDispatchComputeIndirect)     \
  X(PFNGLMEMORYBARRIERPROC, glMemoryBarrier)                         \
  X(PFNGLDRAWELEMENTSINDIRECTPROC, glDrawElementsIndirect)           \
  X(PFNGLCLEARBUFFERDATAPROC, glClearBufferData)                     \
  X(PFNGLUNIFORM1UIPROC, glUniform1ui)                               \
  X(PFNGLUNIFORM1IVPROC, glUniform1iv)                               \
  X(PFNGLBINDBUFFERRANGEPROC, glBindBufferRange)                     \
  X(PFNGLBUFFERSUBDATAPROC, glBufferSubData)                         \
  X(PFNGLCOPYBUFFERSUBDATAPROC, glCopyBufferSubData)

#define LIGHTVOL_GL_DECLARE(type, name) extern type name;
LIGHTVOL_GL_FUNCTIONS(LIGHTVOL_GL_DECLARE)
#undef LIGHTVOL_GL_DECLARE

// The OpenGL version a Context asks EGL for (core profile). lightvol's renderers need 4.5;
// another version is for tests of what they say on an older context.
struct ContextVersion {
  int major = 4, minor = 5;
};

// A headless OpenGL 4.5 core context, current on the creating thread until destroyed.
class Context {
 public:
  // Tries EGL_PLATFORM_SURFACELESS_MESA, then the first EGL device (EGL_EXT_platform_device),
  // then the default display; creates a 4.5 core context without any surface, makes it current
  // and loads the functions above. The Error says what failed at each step ("no OpenGL: ..."),
  // for tests to print when they skip.
  static Result<std::unique_ptr<Context>> create(ContextVersion version = {});

  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // GL_RENDERER and GL_VERSION, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 (Core Profile) ...".
  const std::string& renderer() const { return renderer_; }
  const std::string& version() const { return version_; }
  // Which EGL platform gave the display: "surfaceless", "device" or "default".
  const std::string& platform() const { return platform_; }

 private:
  Context() = default;
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string renderer_, version_, platform_;
};

// For an engine that makes its own OpenGL 4.5 core context (GLFW, SDL, Qt, its own EGL or GLX)
// instead of a Context: loads lightvol's OpenGL functions (the list above) through the engine's
// own loader, with that context current on this thread, once before the first lightvol call:
//
//   lightvol::gl::load_functions(glfwGetProcAddress);     // GLFW
//   lightvol::gl::load_functions(SDL_GL_GetProcAddress);  // SDL 2 (SDL 3 too)
//   lightvol::gl::load_functions(eglGetProcAddress);      // EGL
//
// Every function is resolved before any pointer changes: when the loader has not some (the Error
// names them all, "lightvol::gl::load_functions: the loader has no glDispatchCompute, ..."), the
// pointers stay as they were. After it lightvol draws into whatever context is current when it
// is called (the engine's), and require_context checks that context's version as it checks a
// Context's; whether a context is current is then the engine's to ensure (lightvol cannot ask
// GLX or another loader). The pointers are process-wide, as with a Context: one loader at a time;
// Context::create loads its own again.
using GlProc = void (*)();
Status load_functions(GlProc (*get_proc_address)(const char* name));
Status load_functions(void* (*get_proc_address)(const char* name));

// Owns one GL object name and deletes it on destruction. Move-only.
template <void (*Delete)(GLuint)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(GLuint id) : id_(id) {}
  ~Handle() { reset(); }
  Handle(Handle&& other) noexcept : id_(other.id_) { other.id_ = 0; }
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = other.id_;
      other.id_ = 0;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  GLuint id() const { return id_; }
  void reset() {
    if (id_ != 0) Delete(id_);
    id_ = 0;
  }

 private:
  GLuint id_ = 0;
};

void delete_program(GLuint id);
void delete_texture(GLuint id);
void delete_buffer(GLuint id);
void delete_vertex_array(GLuint id);
void delete_framebuffer(GLuint id);
using ProgramHandle = Handle<delete_program>;
using TextureHandle = Handle<delete_texture>;
using BufferHandle = Handle<delete_buffer>;
using VertexArrayHandle = Handle<delete_vertex_array>;

// A linked shader program.
class Program {
 public:
  // Compiles and links GLSL sources (each starts with its own "#version 450 core"). `name`
  // prefixes the Error, which carries the driver's info log.
  // `feedback` names vertex outputs to capture by transform feedback (interleaved, in order).
  static Result<Program> compile(const std::string& vertex_source,
                                 const std::string& fragment_source, const std::string& name,
                                 const std::vector<std::string>& feedback = {});
  // A compute program from one GLSL source.
  static Result<Program> compile_compute(const std::string& source, const std::string& name);
  GLuint id() const { return handle_.id(); }
  void use() const { glUseProgram(handle_.id()); }
  // Uniform location by name (-1 when the linker dropped it; setting -1 is a no-op in GL).
  GLint uniform(const char* name) const { return glGetUniformLocation(handle_.id(), name); }

 private:
  ProgramHandle handle_;
};

// A 2D texture of `internal_format` (GL_R32F, GL_RG32F, GL_RGBA32F, GL_DEPTH_COMPONENT32F) with
// nearest filtering and clamp-to-edge, filled from `data` (rows bottom-up in GL's convention:
// the first row given is texture row t = 0) or left undefined when `data` is null. `channels` is
// the number of floats per texel in `data`.
TextureHandle make_texture_2d(int width, int height, GLenum internal_format, const float* data,
                              int channels);

// An off-screen framebuffer of float colour attachments and an optional depth buffer.
class Framebuffer {
 public:
  // One colour texture per entry of `color_formats` (GL_R32F, GL_RG32F, GL_RGBA32F), attached
  // to GL_COLOR_ATTACHMENT0.. in order and all enabled as draw buffers; a GL_DEPTH_COMPONENT32F
  // texture when `with_depth`. Errors when the driver reports the framebuffer incomplete.
  static Result<Framebuffer> create(int width, int height, const std::vector<GLenum>& color_formats,
                                    bool with_depth);

  // Binds it as the draw and read framebuffer and sets the viewport to its size.
  void bind() const;
  int width() const { return width_; }
  int height() const { return height_; }
  GLuint color_texture(int i) const { return colors_.at(i).id(); }
  GLuint depth_texture() const { return depth_.id(); }

  // Reads colour attachment `attachment` as `channels` floats per pixel (1 = R, 2 = RG, 4 = RGBA),
  // or the depth attachment when attachment is -1 (channels must be 1). The result is row-major
  // with the first row the TOP of the image (OpenGL's bottom-up rows flipped), like image files.
  std::vector<float> read(int attachment, int channels) const;

 private:
  int width_ = 0, height_ = 0;
  Handle<delete_framebuffer> fbo_;
  std::vector<TextureHandle> colors_;
  TextureHandle depth_;
};

// Measures GPU time of the enclosed work with a GL_TIME_ELAPSED query. begin(); draw...; end();
// then seconds() waits for the result.
class GpuTimer {
 public:
  GpuTimer();
  ~GpuTimer();
  GpuTimer(const GpuTimer&) = delete;
  GpuTimer& operator=(const GpuTimer&) = delete;
  void begin();
  void end();
  double seconds() const;

 private:
  GLuint query_ = 0;
};

// Whether the OpenGL context current on this thread (made by Context::create, which loads the
// functions above, or the engine's, after load_functions) is at least `major`.`minor`, and, with
// `compute`, has compute shaders (4.3 or later). The Error names `what` needs it and what the
// context is, e.g. "live volume: needs OpenGL 4.5 core; the current context is OpenGL 3.3 (llvmpipe
// ...)", or says that no context is current. Renderers call it before any other GL call, so an old
// context is an Error value, never a GL error or a crash at draw time.
Status require_context(int major, int minor, bool compute, const std::string& what);

// The first pending glGetError as text ("GL_INVALID_OPERATION"), or empty when there is none.
std::string pending_error();

}  // namespace lightvol::gl
