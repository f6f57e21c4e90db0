// An engine's frame loop through the installed package (docs/rendering.md, "Live volumes"): the
// engine draws its scene (a floor and a box that moves between frames) with its own shaders into a
// depth texture from the light and, with the installed shaders/airlight.glsl's surface stages,
// into the camera's distance texture; hands both textures to lightvol (LiveVolume,
// GlVolumeRenderer::set_surface) and draws the airlight. Nothing goes back to the CPU in the
// loop; the check after each frame reads the depth texture back, builds the volume on the CPU
// (build_static_volume) and renders it with the CPU reference (double precision): the live
// image must be that frame's to 1e-3 relative L2, lit somewhere, zero where the reference is, and
// differ between frames where the box moved.
//
// The context is the engine's own, made with EGL as GLFW or SDL would make one, and lightvol's
// OpenGL functions are loaded through the engine's loader (lightvol::gl::load_functions with
// eglGetProcAddress); where CMake finds no EGL to link, through lightvol::gl::Context instead.
//
//   engine_loop [SHADER_DIR]   (default: the package's lightvol_SHADER_DIR, built in)
//
// Exit 0 when every frame passes; 1 on a failed check; 77 (and a line saying why) when no OpenGL
// 4.5 context can be made, unless LIGHTVOL_REQUIRE_GL is set, which makes that a failure too.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/gl/context.h>
#include <lightvol/light/light.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>
#include <lightvol/render/reference.h>
#include <lightvol/volume/static_volume.h>

#ifdef ENGINE_OWN_EGL
#include <EGL/egl.h>
#include <EGL/eglext.h>
#endif

using namespace lightvol;
using namespace lightvol::gl;

namespace {

#ifdef ENGINE_OWN_EGL
// The engine's own headless OpenGL 4.5 core context (Mesa's surfaceless platform, else the
// default display), current on this thread while it lives.
struct EngineContext {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EngineContext() = default;
  EngineContext(const EngineContext&) = delete;
  EngineContext& operator=(const EngineContext&) = delete;
  ~EngineContext() {
    if (display == EGL_NO_DISPLAY) return;
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
    eglTerminate(display);
  }
  // "" when current; else what failed.
  std::string make() {
    const auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (platform_display != nullptr)
      display = platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY || eglInitialize(display, nullptr, nullptr) != EGL_TRUE) {
      display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
      if (display == EGL_NO_DISPLAY || eglInitialize(display, nullptr, nullptr) != EGL_TRUE) {
        display = EGL_NO_DISPLAY;
        return "no EGL display";
      }
    }
    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) return "eglBindAPI(EGL_OPENGL_API) failed";
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 4,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) return "cannot create an OpenGL 4.5 core context";
    if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE)
      return "cannot make the context current";
    return "";
  }
};
#endif

// Exit code when there is no OpenGL 4.5 context: 77 (skipped), or 1 under LIGHTVOL_REQUIRE_GL.
int no_context(const std::string& why) {
  const char* require = std::getenv("LIGHTVOL_REQUIRE_GL");
  std::fprintf(stderr, "engine_loop: no OpenGL 4.5 context: %s\n", why.c_str());
  return require && *require && std::string(require) != "0" ? 1 : 77;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "engine_loop: %s\n", message.c_str());
  return 1;
}

// The engine's scene: a floor 8 × 8 at y = 0 and a box 1 × 0.6 × 1 at height 1 to 1.6 whose
// centre is at x = `box_x`; world-space triangles.
std::vector<float> scene_triangles(double box_x) {
  std::vector<float> t;
  const auto quad = [&t](const float(&a)[3], const float(&b)[3], const float(&c)[3],
                         const float(&d)[3]) {
    for (const float* p : {a, b, c, a, c, d}) t.insert(t.end(), p, p + 3);
  };
  quad({-4, 0, -4}, {-4, 0, 4}, {4, 0, 4}, {4, 0, -4});
  const float x0 = static_cast<float>(box_x - 0.5), x1 = static_cast<float>(box_x + 0.5);
  const float y0 = 1.0f, y1 = 1.6f, z0 = -0.5f, z1 = 0.5f;
  quad({x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0});  // top
  quad({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1});  // bottom
  quad({x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0});  // −x
  quad({x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1});  // +x
  quad({x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0});  // −z
  quad({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1});  // +z
  return t;
}

// The engine's own depth pass: positions at location 0, one matrix.
constexpr const char* kDepthVertex = R"(#version 450 core
layout(location = 0) in vec3 position;
uniform mat4 view_projection;
void main() { gl_Position = view_projection * vec4(position, 1.0); }
)";
constexpr const char* kDepthFragment = "#version 450 core\nvoid main() {}\n";

void set_matrix(const Program& program, const Mat4d& m) {
  float f[16];
  for (int i = 0; i < 16; ++i) f[i] = static_cast<float>(m.m[i]);
  glUniformMatrix4fv(program.uniform("view_projection"), 1, GL_TRUE, f);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return in ? text.str() : std::string();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 2) return fail("usage: engine_loop [SHADER_DIR]");
  const std::string dir = argc == 2 ? argv[1] : LIGHTVOL_SHADER_DIR;
  const std::string shader = read_file(dir + "/airlight.glsl");
  if (shader.empty()) return fail(dir + "/airlight.glsl: not installed");

#ifdef ENGINE_OWN_EGL
  EngineContext context;
  if (const std::string why = context.make(); !why.empty()) return no_context(why);
  if (Status loaded = load_functions(eglGetProcAddress); !loaded)
    return fail(loaded.error().message);
  std::printf("engine_loop: the engine's EGL context, %s\n",
              reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
#else
  Result<std::unique_ptr<Context>> context = Context::create();
  if (!context) return no_context(context.error().message);
  std::printf("engine_loop: %s\n", (*context)->renderer().c_str());
#endif

  Result<Light> light = parse_light(
      R"({"type": "spot", "position": [0.3, 4, 0.2], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 70, "near": 0.5, "far": 10, "depth": "window"})",
      "engine light");
  Result<Camera> camera = parse_camera(
      R"({"type": "spot", "position": [5, 2.5, 5.5], "direction": [-5, -1.6, -5.5],
          "up": [0, 1, 0], "fov_y_deg": 50, "aspect": 1.3333333333, "near": 0.1, "far": 40,
          "depth": "window", "width": 128, "height": 96})",
      "engine camera");
  Result<Medium> medium = parse_medium(
      R"({"scattering": 0.1, "absorption": 0.01, "intensity": 40, "phase": {"type": "hg", "g": 0.3}})",
      "engine medium");
  if (!light || !camera || !medium) return fail("the scene's JSON does not parse");
  RenderScene scene;
  scene.camera = *camera;
  scene.light = *light;
  scene.medium = *medium;
  scene.surface.assign(static_cast<std::size_t>(camera->width) * camera->height, INFINITY);

  // The engine's GPU resources, made once.
  constexpr int kMap = 96;
  Result<Framebuffer> shadow = Framebuffer::create(kMap, kMap, {}, /*with_depth=*/true);
  Result<Framebuffer> surface =
      Framebuffer::create(camera->width, camera->height, {GL_R32F}, /*with_depth=*/true);
  Result<Program> depth_pass = Program::compile(kDepthVertex, kDepthFragment, "engine depth");
  // The surface pass from the installed shader file, as docs/engines.md prescribes.
  Result<Program> surface_pass =
      Program::compile("#version 450 core\n#define LIGHTVOL_SURFACE_VERTEX\n" + shader,
                       "#version 450 core\n#define LIGHTVOL_SURFACE_FRAGMENT\n" + shader,
                       "installed airlight.glsl, surface pass");
  if (!shadow) return fail(shadow.error().message);
  if (!surface) return fail(surface.error().message);
  if (!depth_pass) return fail(depth_pass.error().message);
  if (!surface_pass) return fail(surface_pass.error().message);
  surface_pass->use();
  set_scene_uniforms(*surface_pass, scene);
  set_matrix(*surface_pass, camera->view.projection * camera->view.view);
  GLuint vao = 0, vbo = 0;
  glGenVertexArrays(1, &vao);
  glGenBuffers(1, &vbo);
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindVertexArray(0);

  // lightvol, set up once: the live volume reads the shadow framebuffer's depth texture.
  const GlShadowMap map{shadow->depth_texture(), kMap, kMap};
  Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(*light, map);
  if (!live) return fail(live.error().message);
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
  if (!renderer) return fail(renderer.error().message);
  if (Status s = (*renderer)->set_volume(**live); !s) return fail(s.error().message);
  if (Status s = (*renderer)->set_surface(surface->color_texture(0)); !s)
    return fail(s.error().message);

  Image previous;
  for (int frame = 0; frame < 3; ++frame) {
    // The engine's frame: move the box, draw the light's depth pass and the camera's surface pass.
    const std::vector<float> triangles = scene_triangles(-1.2 + 1.2 * frame);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(triangles.size() * sizeof(float)),
                 triangles.data(), GL_DYNAMIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    const GLsizei vertices = static_cast<GLsizei>(triangles.size() / 3);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glBindVertexArray(vao);
    shadow->bind();
    glClearDepth(1.0);
    glClear(GL_DEPTH_BUFFER_BIT);
    depth_pass->use();
    set_matrix(*depth_pass, light->projection * light->view);
    glDrawArrays(GL_TRIANGLES, 0, vertices);
    surface->bind();
    glClearColor(3e38f, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    surface_pass->use();
    glDrawArrays(GL_TRIANGLES, 0, vertices);
    glBindVertexArray(0);
    glDisable(GL_DEPTH_TEST);
    // lightvol's part of the frame: the volume from the depth texture, the airlight.
    const Image airlight = (*renderer)->render();
    if (const std::string e = pending_error(); !e.empty()) return fail("OpenGL: " + e);

    // The check, outside the loop's work: the CPU's volume of the same map, drawn by the CPU.
    DepthImage depth;
    depth.width = depth.height = kMap;
    depth.values = shadow->read(-1, 1);  // first row = top: the image file order (flip_y off)
    Result<Mesh> mesh = build_static_volume(*light, depth, {}, "frame " + std::to_string(frame));
    if (!mesh) return fail(mesh.error().message);
    RenderScene cpu = scene;
    const std::vector<float> distances = surface->read(0, 1);
    for (std::size_t i = 0; i < distances.size(); ++i)
      cpu.surface[i] = distances[i] >= 1e38f ? INFINITY : static_cast<double>(distances[i]);
    const Image reference = render_reference(*mesh, cpu);
    const ImageDifference d = compare_images(airlight, reference);
    double total = 0, peak = 0, dark_peak = 0;
    std::size_t dark = 0;
    for (std::size_t i = 0; i < reference.values.size(); ++i) {
      total += airlight.values[i];
      peak = std::max(peak, std::abs(reference.values[i]));
      if (reference.values[i] == 0) {
        ++dark;
        dark_peak = std::max(dark_peak, std::abs(airlight.values[i]));
      }
    }
    const double moved = frame == 0 ? 0 : compare_images(airlight, previous).relative_l2;
    std::printf(
        "engine_loop: frame %d: %zu triangles, relative L2 %.2e against the CPU's volume and "
        "reference, %zu pixels unlit (live there at most %.1e), change from the last frame "
        "%.2e\n",
        frame, mesh->num_triangles(), d.relative_l2, dark, dark_peak, moved);
    if (!(total > 0)) return fail("frame " + std::to_string(frame) + ": no airlight");
    if (!(d.relative_l2 <= 1e-3)) return fail("frame " + std::to_string(frame) + ": not the CPU's");
    if (dark == 0 || dark_peak > 1e-6 * peak)
      return fail("frame " + std::to_string(frame) + ": unlit pixels lit");
    if (frame > 0 && !(moved > 0.01))
      return fail("frame " + std::to_string(frame) + ": the box moved, the airlight did not");
    previous = airlight;
  }
  glDeleteBuffers(1, &vbo);
  glDeleteVertexArrays(1, &vao);
  std::printf("engine_loop: 3 frames, each the CPU-built volume's airlight\n");
  return 0;
}
