#include <dlfcn.h>

#include <cstdio>
#include <cstring>
#include <mutex>

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <lightvol/core/check.h>
#include <lightvol/gl/context.h>

namespace lightvol::gl {

#define LIGHTVOL_GL_DEFINE(type, name) type name = nullptr;
LIGHTVOL_GL_FUNCTIONS(LIGHTVOL_GL_DEFINE)
#undef LIGHTVOL_GL_DEFINE

namespace {

// libEGL is opened when the first context is created (dlopen), not linked: linking it made every
// lightvol command load EGL, GLdispatch and GLX at start, rendering or not. These pointers, named
// as EGL's functions, are what the calls below resolve to (this namespace is searched before the
// global one).
// clang-format off
#define LIGHTVOL_EGL_FUNCTIONS(X)                                                      \
  X(eglBindAPI) X(eglChooseConfig) X(eglCreateContext) X(eglDestroyContext)            \
  X(eglGetDisplay) X(eglGetError) X(eglGetProcAddress) X(eglInitialize)                \
  X(eglMakeCurrent) X(eglQueryString) X(eglTerminate) X(eglGetCurrentContext)
// clang-format on
#define LIGHTVOL_EGL_DEFINE(name) decltype(&::name) name = nullptr;
LIGHTVOL_EGL_FUNCTIONS(LIGHTVOL_EGL_DEFINE)
#undef LIGHTVOL_EGL_DEFINE

// Opens libEGL.so.1 and resolves the functions above, once; an Error saying why it could not.
Status load_egl() {
  static std::once_flag once;
  static std::string failure;
  std::call_once(once, [] {
    void* library = ::dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
      const char* why = ::dlerror();
      failure = "cannot load libEGL.so.1 (" + std::string(why ? why : "unknown reason") + ")";
      return;
    }
#define LIGHTVOL_EGL_LOAD(name)                                     \
  name = reinterpret_cast<decltype(name)>(::dlsym(library, #name)); \
  if (name == nullptr && failure.empty()) failure = "libEGL.so.1 has no " #name;
    LIGHTVOL_EGL_FUNCTIONS(LIGHTVOL_EGL_LOAD)
#undef LIGHTVOL_EGL_LOAD
  });
  if (!failure.empty()) return Error{failure};
  return {};
}

// Whether the functions came from an engine's loader (load_functions) rather than a Context.
bool g_engine_loader = false;

// Resolves every function of LIGHTVOL_GL_FUNCTIONS with `get`, then sets the pointers; when some
// are missing, sets none and returns their names ("glA, glB").
template <typename Get>
std::string load_all(Get get) {
  std::string missing;
#define LIGHTVOL_GL_RESOLVE(type, name)                            \
  const auto resolved_##name = reinterpret_cast<type>(get(#name)); \
  if (resolved_##name == nullptr) missing += std::string(missing.empty() ? "" : ", ") + #name;
  LIGHTVOL_GL_FUNCTIONS(LIGHTVOL_GL_RESOLVE)
#undef LIGHTVOL_GL_RESOLVE
  if (!missing.empty()) return missing;
#define LIGHTVOL_GL_ASSIGN(type, name) name = resolved_##name;
  LIGHTVOL_GL_FUNCTIONS(LIGHTVOL_GL_ASSIGN)
#undef LIGHTVOL_GL_ASSIGN
  return "";
}

Status load_through(const std::string& missing) {
  if (!missing.empty()) return Error{"lightvol::gl::load_functions: the loader has no " + missing};
  g_engine_loader = true;
  return {};
}

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default:
      return "EGL error " + std::to_string(code);
  }
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// A display on the first platform that initializes; `platform` names it.
EGLDisplay open_display(std::string* platform, std::string* why) {
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  auto try_display = [&](EGLDisplay d, const char* name) -> EGLDisplay {
    if (d == EGL_NO_DISPLAY) {
      *why += std::string(why->empty() ? "" : "; ") + name + ": no display";
      return EGL_NO_DISPLAY;
    }
    EGLint major = 0, minor = 0;
    if (eglInitialize(d, &major, &minor) != EGL_TRUE) {
      *why += std::string(why->empty() ? "" : "; ") + name + ": eglInitialize failed (" +
              egl_error_name(eglGetError()) + ")";
      return EGL_NO_DISPLAY;
    }
    *platform = name;
    return d;
  };

  if (get_platform_display != nullptr &&
      has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = try_display(
        get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
        "surfaceless");
    if (d != EGL_NO_DISPLAY) return d;
  }
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (get_platform_display != nullptr && query_devices != nullptr &&
      has_extension(client_ext, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[8];
    EGLint count = 0;
    if (query_devices(8, devices, &count) == EGL_TRUE && count > 0) {
      EGLDisplay d =
          try_display(get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[0], nullptr), "device");
      if (d != EGL_NO_DISPLAY) return d;
    }
  }
  return try_display(eglGetDisplay(EGL_DEFAULT_DISPLAY), "default");
}

}  // namespace

Result<std::unique_ptr<Context>> Context::create(ContextVersion version) {
  if (Status loaded = load_egl(); !loaded) return Error{"no OpenGL: " + loaded.error().message};
  std::string platform, why;
  EGLDisplay display = open_display(&platform, &why);
  if (display == EGL_NO_DISPLAY)
    return Error{"no OpenGL: no EGL display could be opened (" + why + ")"};

  auto fail = [&](const std::string& what) -> Error {
    const std::string message = "no OpenGL: " + what + " (" + egl_error_name(eglGetError()) +
                                ", EGL platform " + platform + ")";
    eglTerminate(display);
    return Error{message};
  };

  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) return fail("eglBindAPI(EGL_OPENGL_API) failed");
  const char* display_ext = eglQueryString(display, EGL_EXTENSIONS);
  EGLConfig config = nullptr;
  if (!has_extension(display_ext, "EGL_KHR_no_config_context")) {
    const EGLint attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint count = 0;
    if (eglChooseConfig(display, attributes, &config, 1, &count) != EGL_TRUE || count < 1)
      return fail("no EGL config renders OpenGL");
  }
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       version.major,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       version.minor,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
  if (context == EGL_NO_CONTEXT)
    return fail("cannot create an OpenGL " + std::to_string(version.major) + "." +
                std::to_string(version.minor) + " core context");
  if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE) {
    eglDestroyContext(display, context);
    return fail("cannot make a surfaceless OpenGL context current");
  }

  const std::string missing = load_all([](const char* name) { return eglGetProcAddress(name); });
  if (!missing.empty()) {
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, context);
    return fail("missing OpenGL functions: " + missing);
  }

  g_engine_loader = false;
  std::unique_ptr<Context> result(new Context());
  result->display_ = display;
  result->context_ = context;
  result->platform_ = platform;
  auto text = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
  };
  result->renderer_ = text(GL_RENDERER);
  result->version_ = text(GL_VERSION);
  return result;
}

Context::~Context() {
  auto display = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, static_cast<EGLContext>(context_));
  eglTerminate(display);
}

Status load_functions(GlProc (*get_proc_address)(const char* name)) {
  return load_through(load_all(get_proc_address));
}

Status load_functions(void* (*get_proc_address)(const char* name)) {
  return load_through(load_all(get_proc_address));
}

Status require_context(int major, int minor, bool compute, const std::string& what) {
  const std::string needs = what + ": needs OpenGL " + std::to_string(major) + "." +
                            std::to_string(minor) + " core" +
                            (compute ? " with compute shaders" : "") + "; ";
  if (glGetIntegerv == nullptr ||
      (!g_engine_loader &&
       (eglGetCurrentContext == nullptr || eglGetCurrentContext() == EGL_NO_CONTEXT)) ||
      (g_engine_loader && glGetString(GL_VERSION) == nullptr))
    return Error{needs +
                 "no OpenGL context is current on this thread (lightvol::gl::Context::create "
                 "makes one and loads lightvol's OpenGL functions)"};
  GLint have_major = 0, have_minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &have_major);
  glGetIntegerv(GL_MINOR_VERSION, &have_minor);
  GLint invocations = 0;
  if (have_major > 4 || (have_major == 4 && have_minor >= 3))
    glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &invocations);
  (void)pending_error();
  const bool old = have_major < major || (have_major == major && have_minor < minor);
  if (!old && (!compute || invocations > 0)) return {};
  const GLubyte* renderer = glGetString(GL_RENDERER);
  return Error{needs + "the current context is OpenGL " + std::to_string(have_major) + "." +
               std::to_string(have_minor) +
               (compute && invocations <= 0 ? ", without compute shaders" : "") + " (" +
               (renderer ? reinterpret_cast<const char*>(renderer) : "unknown renderer") + ")"};
}

// ---- objects ------------------------------------------------------------------------------------

void delete_program(GLuint id) { glDeleteProgram(id); }
void delete_texture(GLuint id) { glDeleteTextures(1, &id); }
void delete_buffer(GLuint id) { glDeleteBuffers(1, &id); }
void delete_vertex_array(GLuint id) { glDeleteVertexArrays(1, &id); }
void delete_framebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }

namespace {

Result<GLuint> compile_shader(GLenum stage, const std::string& source, const std::string& name) {
  const GLuint shader = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok == GL_TRUE) return shader;
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
  glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
  glDeleteShader(shader);
  const char* kind = stage == GL_VERTEX_SHADER    ? "vertex"
                     : stage == GL_COMPUTE_SHADER ? "compute"
                                                  : "fragment";
  return Error{name + ": " + kind + " shader does not compile: " + log.c_str()};
}

// The link of program `id` as a value: its log on failure.
Status link_status(GLuint id, const std::string& name) {
  GLint ok = GL_FALSE;
  glGetProgramiv(id, GL_LINK_STATUS, &ok);
  if (ok == GL_TRUE) return {};
  GLint length = 0;
  glGetProgramiv(id, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
  glGetProgramInfoLog(id, static_cast<GLsizei>(log.size()), nullptr, log.data());
  return Error{name + ": program does not link: " + log.c_str()};
}

}  // namespace

Result<Program> Program::compile(const std::string& vertex_source,
                                 const std::string& fragment_source, const std::string& name,
                                 const std::vector<std::string>& feedback) {
  Result<GLuint> vs = compile_shader(GL_VERTEX_SHADER, vertex_source, name);
  if (!vs) return vs.error();
  Result<GLuint> fs = compile_shader(GL_FRAGMENT_SHADER, fragment_source, name);
  if (!fs) {
    glDeleteShader(*vs);
    return fs.error();
  }
  Program program;
  program.handle_ = ProgramHandle(glCreateProgram());
  const GLuint id = program.handle_.id();
  glAttachShader(id, *vs);
  glAttachShader(id, *fs);
  if (!feedback.empty()) {
    std::vector<const char*> names;
    for (const std::string& n : feedback) names.push_back(n.c_str());
    glTransformFeedbackVaryings(id, static_cast<GLsizei>(names.size()), names.data(),
                                GL_INTERLEAVED_ATTRIBS);
  }
  glLinkProgram(id);
  glDeleteShader(*vs);
  glDeleteShader(*fs);
  if (Status linked = link_status(id, name); !linked) return linked.error();
  return program;
}

Result<Program> Program::compile_compute(const std::string& source, const std::string& name) {
  Result<GLuint> cs = compile_shader(GL_COMPUTE_SHADER, source, name);
  if (!cs) return cs.error();
  Program program;
  program.handle_ = ProgramHandle(glCreateProgram());
  const GLuint id = program.handle_.id();
  glAttachShader(id, *cs);
  glLinkProgram(id);
  glDeleteShader(*cs);
  if (Status linked = link_status(id, name); !linked) return linked.error();
  return program;
}

namespace {

GLenum format_of(GLenum internal_format) {
  switch (internal_format) {
    case GL_R32F:
      return GL_RED;
    case GL_RG32F:
      return GL_RG;
    case GL_RGB32F:
      return GL_RGB;
    case GL_RGBA32F:
      return GL_RGBA;
    case GL_DEPTH_COMPONENT32F:
      return GL_DEPTH_COMPONENT;
    default:
      break;
  }
  LV_CHECK(!"unsupported internal format");
  return GL_RED;
}

GLenum format_of_channels(int channels) {
  switch (channels) {
    case 1:
      return GL_RED;
    case 2:
      return GL_RG;
    case 3:
      return GL_RGB;
    case 4:
      return GL_RGBA;
    default:
      break;
  }
  LV_CHECK(!"channels must be 1, 2, 3 or 4");
  return GL_RED;
}

}  // namespace

TextureHandle make_texture_2d(int width, int height, GLenum internal_format, const float* data,
                              int channels) {
  GLuint id = 0;
  glGenTextures(1, &id);
  glBindTexture(GL_TEXTURE_2D, id);
  const GLenum format = internal_format == GL_DEPTH_COMPONENT32F
                            ? GL_DEPTH_COMPONENT
                            : (data ? format_of_channels(channels) : format_of(internal_format));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal_format), width, height, 0, format,
               GL_FLOAT, data);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_2D, 0);
  return TextureHandle(id);
}

Result<Framebuffer> Framebuffer::create(int width, int height,
                                        const std::vector<GLenum>& color_formats, bool with_depth) {
  LV_CHECK(width > 0 && height > 0);
  Framebuffer fb;
  fb.width_ = width;
  fb.height_ = height;
  GLuint id = 0;
  glGenFramebuffers(1, &id);
  fb.fbo_ = Handle<delete_framebuffer>(id);
  glBindFramebuffer(GL_FRAMEBUFFER, id);
  std::vector<GLenum> draw_buffers;
  for (std::size_t i = 0; i < color_formats.size(); ++i) {
    fb.colors_.push_back(make_texture_2d(width, height, color_formats[i], nullptr, 0));
    const GLenum attachment = GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i);
    glFramebufferTexture2D(GL_FRAMEBUFFER, attachment, GL_TEXTURE_2D, fb.colors_.back().id(), 0);
    draw_buffers.push_back(attachment);
  }
  if (with_depth) {
    fb.depth_ = make_texture_2d(width, height, GL_DEPTH_COMPONENT32F, nullptr, 1);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, fb.depth_.id(), 0);
  }
  if (draw_buffers.empty()) {
    const GLenum none = GL_NONE;
    glDrawBuffers(1, &none);
  } else {
    glDrawBuffers(static_cast<GLsizei>(draw_buffers.size()), draw_buffers.data());
  }
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    return Error{"OpenGL: framebuffer " + std::to_string(width) + "x" + std::to_string(height) +
                 " is incomplete (status 0x" +
                 [&] {
                   char buf[16];
                   std::snprintf(buf, sizeof buf, "%x", status);
                   return std::string(buf);
                 }() +
                 ")"};
  return fb;
}

void Framebuffer::bind() const {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glViewport(0, 0, width_, height_);
}

std::vector<float> Framebuffer::read(int attachment, int channels) const {
  LV_CHECK(attachment >= -1 && attachment < static_cast<int>(colors_.size()));
  const std::size_t w = static_cast<std::size_t>(width_), h = static_cast<std::size_t>(height_);
  const std::size_t c = static_cast<std::size_t>(channels);
  std::vector<float> gl_rows(w * h * c);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  if (attachment < 0) {
    LV_CHECK_EQ(channels, 1);
    glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, gl_rows.data());
  } else {
    glReadBuffer(GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(attachment));
    glReadPixels(0, 0, width_, height_, format_of_channels(channels), GL_FLOAT, gl_rows.data());
  }
  std::vector<float> image(gl_rows.size());
  for (std::size_t row = 0; row < h; ++row)
    std::memcpy(&image[row * w * c], &gl_rows[(h - 1 - row) * w * c], w * c * sizeof(float));
  return image;
}

GpuTimer::GpuTimer() { glGenQueries(1, &query_); }
GpuTimer::~GpuTimer() { glDeleteQueries(1, &query_); }
void GpuTimer::begin() { glBeginQuery(GL_TIME_ELAPSED, query_); }
void GpuTimer::end() { glEndQuery(GL_TIME_ELAPSED); }
double GpuTimer::seconds() const {
  GLuint64 ns = 0;
  glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &ns);
  return static_cast<double>(ns) * 1e-9;
}

std::string pending_error() {
  const GLenum e = glGetError();
  switch (e) {
    case GL_NO_ERROR:
      return {};
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    default:
      return "GL error " + std::to_string(e);
  }
}

}  // namespace lightvol::gl
