#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <lightvol/core/check.h>
#include <lightvol/render/detail/density_glsl.h>
#include <lightvol/render/detail/density_grid_glsl.h>
#include <lightvol/render/gl_density.h>
#include <lightvol/render/gl_volume.h>

namespace lightvol {

using namespace gl;

const char* const kGlslDensity = detail::kDensityGlsl;

namespace {
void set_matrix(const Program& p, const std::string& name, const Mat4d& m);
}  // namespace

void set_density_uniforms(const Program& program, const Density& density) {
  const NoiseDensity& n = density.noise;
  const bool grid = density.type == DensityType::grid;
  glUniform1i(program.uniform("density_type"), grid ? 2 : density.varying() ? 1 : 0);
  glUniform1i(program.uniform("density_grid"), kDensityTextureUnit);
  if (grid) {
    const VoxelGrid& g = *density.grid;
    Mat4d to_texel;  // the index map less the box's first index, in double before float
    to_texel(0, 3) = -g.origin[0];
    to_texel(1, 3) = -g.origin[1];
    to_texel(2, 3) = -g.origin[2];
    set_matrix(program, "density_world_to_texel", to_texel * g.world_to_index);
    glUniform3f(program.uniform("density_grid_size"), static_cast<float>(g.dims[0]),
                static_cast<float>(g.dims[1]), static_cast<float>(g.dims[2]));
    glUniform1f(program.uniform("density_grid_background"), static_cast<float>(g.background));
  }
  glUniform1ui(program.uniform("density_seed"), n.seed);
  glUniform1f(program.uniform("density_frequency"), static_cast<float>(n.frequency));
  glUniform1i(program.uniform("density_octaves"), n.octaves);
  glUniform1f(program.uniform("density_lacunarity"), static_cast<float>(n.lacunarity));
  glUniform1f(program.uniform("density_gain"), static_cast<float>(n.gain));
  glUniform1f(program.uniform("density_offset"), static_cast<float>(n.offset));
  glUniform1f(program.uniform("density_scale"), static_cast<float>(n.scale));
}

// ---- the density field -------------------------------------------------------------------------

GlDensityField::~GlDensityField() = default;

Result<std::shared_ptr<const GlDensityField>> GlDensityField::create(const Density& density) {
  std::shared_ptr<GlDensityField> field(new GlDensityField());
  field->density_ = density;
  if (density.type != DensityType::grid) return std::shared_ptr<const GlDensityField>(field);
  const VoxelGrid& g = *density.grid;
  GLint most = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &most);
  for (int axis = 0; axis < 3; ++axis)
    if (g.dims[axis] > most)
      return Error{g.source + ": " + std::to_string(g.dims[0]) + "x" + std::to_string(g.dims[1]) +
                   "x" + std::to_string(g.dims[2]) + " voxels; this OpenGL driver's 3D textures " +
                   "hold at most " + std::to_string(most) + " along each axis"};
  GLuint id = 0;
  glGenTextures(1, &id);
  field->texture_ = TextureHandle(id);
  glActiveTexture(GL_TEXTURE0 + kDensityTextureUnit);
  glBindTexture(GL_TEXTURE_3D, id);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, g.dims[0], g.dims[1], g.dims[2], 0, GL_RED, GL_FLOAT,
               g.values.data());
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAX_LEVEL, 0);
  glActiveTexture(GL_TEXTURE0);
  if (std::string e = pending_error(); !e.empty())
    return Error{g.source + ": OpenGL: uploading the grid as a 3D texture: " + e};
  return std::shared_ptr<const GlDensityField>(field);
}

void GlDensityField::bind(const Program& program) const {
  set_density_uniforms(program, density_);
  bind_texture();
}

void GlDensityField::bind_texture() const {
  if (!texture_.id()) return;
  glActiveTexture(GL_TEXTURE0 + kDensityTextureUnit);
  glBindTexture(GL_TEXTURE_3D, texture_.id());
  glActiveTexture(GL_TEXTURE0);
}

namespace {

void set_matrix(const Program& p, const std::string& name, const Mat4d& m) {
  float v[16];
  for (int i = 0; i < 16; ++i) v[i] = static_cast<float>(m.m[i]);
  glUniformMatrix4fv(p.uniform(name.c_str()), 1, GL_TRUE, v);
}

BufferHandle make_storage(std::size_t floats, const float* data) {
  GLuint id = 0;
  glGenBuffers(1, &id);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, id);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(floats * sizeof(float)), data,
               GL_DYNAMIC_COPY);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  return BufferHandle(id);
}

// The opacity map's compute shader (after density.glsl and density_grid.glsl's uniforms).
const char* const kOpacityBuild = R"(
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 3) writeonly buffer OpacityMap { float om_tau[]; };
uniform int om_substeps;
uniform float om_sigma_t;
void main() {
  ivec3 id = ivec3(gl_GlobalInvocationID);
  if (id.x >= om_size || id.y >= om_size) return;
  vec2 ndc = (2.0 * vec2(id.xy) + 1.0) / float(om_size) - 1.0;
  vec4 n = om_clip_to_world[id.z] * vec4(ndc, -1.0, 1.0);
  vec4 f = om_clip_to_world[id.z] * vec4(ndc, 1.0, 1.0);
  vec3 pn = n.xyz / n.w, pf = f.xyz / f.w;
  vec3 origin = om_point == 1 ? om_light_position : pn;
  vec3 dir = normalize(om_point == 1 ? pn - om_light_position : pf - pn);
  int base = ((id.z * om_size + id.y) * om_size + id.x) * om_layers;
  float layer = om_range / float(om_layers - 1);
  float h = layer / float(om_substeps);
  float tau = 0.0;
  om_tau[base] = 0.0;
  for (int k = 1; k < om_layers; ++k) {
    float sum = 0.0;
    for (int j = 0; j < om_substeps; ++j)
      sum += density(origin + ((float(k - 1) + (float(j) + 0.5) / float(om_substeps)) * layer) * dir);
    tau += om_sigma_t * sum * h;
    om_tau[base + k] = tau;
  }
}
)";

// The opacity map's look-up, shaders/density_grid.glsl's, reading the map from storage buffer 3.
const std::string kOpacityLookupSource =
    std::string(
        "#define LIGHTVOL_OPACITY_LOOKUP\n"
        "layout(std430, binding = 3) readonly buffer OpacityMap { float om_tau[]; };\n"
        "#define om_fetch(face, c, r, k) "
        "om_tau[(((face) * om_size + (r)) * om_size + (c)) * om_layers + (k)]\n") +
    detail::kDensityGridGlsl;

// The grid's compute shader: airlight.glsl's common part (its pixel_ray reads gl_FragCoord, which
// a compute shader does not have: here it is the column's centre), the density, the opacity map
// and density_grid.glsl's d_integrand.
const char* const kGridBuild = R"(
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 4) writeonly buffer DensityGrid { vec2 grid_d[]; };
layout(std430, binding = 5) readonly buffer DensityColumns { float grid_t1[]; };
uniform ivec2 grid_columns;
uniform int grid_tile;
uniform int grid_slices;
uniform int grid_substeps;
void main() {
  ivec2 id = ivec2(gl_GlobalInvocationID.xy);
  if (id.x >= grid_columns.x || id.y >= grid_columns.y) return;
  int column = id.y * grid_columns.x + id.x;
  lv_frag_coord = vec4((vec2(id) + 0.5) * float(grid_tile), 0.0, 1.0);
  pixel_ray(g_ray_origin, g_ray_dir);
  float t1 = grid_t1[column];
  int base = column * grid_slices;
  if (!(t1 > 0.0)) {  // no pixel reads this column
    for (int k = 0; k < grid_slices; ++k) grid_d[base + k] = vec2(0.0);
    return;
  }
  // Slices uniform in grid_coordinate (airlight.glsl; density_grid.glsl's grid_node).
  float psi1 = light_type == 1 ? 0.0 : grid_light_angle(light_position - g_ray_origin, g_ray_dir, t1);
  float dw = 1.0 / float(grid_slices - 1);
  float tau_e = 0.0, d = 0.0, t0 = 0.0;
  // Each slice boundary keeps D and its derivative in w (the integrand times dt/dw), for cubic
  // Hermite look-ups.
  grid_d[base] = vec2(0.0, d_integrand(0.0, density(g_ray_origin), 0.0) /
                               grid_coordinate_rate(0.0, t1, psi1));
  for (int k = 1; k < grid_slices; ++k) {
    float tk = grid_node(float(k) * dw, t0, t1, psi1);
    float dt = (tk - t0) / float(grid_substeps);
    for (int j = 0; j < grid_substeps; ++j) {
      float t = t0 + (float(j) + 0.5) * dt;
      float rho = density(g_ray_origin + t * g_ray_dir);
      d += d_integrand(t, rho, tau_e + 0.5 * sigma_t * rho * dt) * dt;
      tau_e += sigma_t * rho * dt;
    }
    grid_d[base + k] = vec2(d, d_integrand(tk, density(g_ray_origin + tk * g_ray_dir), tau_e) /
                                   grid_coordinate_rate(tk, t1, psi1));
    t0 = tk;
  }
}
)";

std::string compute_header() {
  return "#version 450 core\n#define gl_FragCoord lv_frag_coord\nvec4 lv_frag_coord;\n";
}

}  // namespace

const char* const kGlslOpacityLookup = kOpacityLookupSource.c_str();

// ---- the automatic tile -------------------------------------------------------------------------

namespace {

// One column per pixel while the grid stays within 2^25 samples (256 MB); coarser beyond. (Columns
// wider than a pixel interpolate D across rays: a point light's by angle from the light,
// docs/design.md §6; the density's own finest features across columns are then what they miss.)
int automatic_tile(const RenderScene& scene, int slices) {
  const Camera& cam = scene.camera;
  int tile = 1;
  // At most 2^25 samples (256 MB).
  const auto samples = [&](int t) {
    return static_cast<double>((cam.width + t - 1) / t) * ((cam.height + t - 1) / t) * slices;
  };
  while (samples(tile) > 33554432.0 && tile < 256) ++tile;
  return tile;
}

}  // namespace

// ---- light bounds -------------------------------------------------------------------------------

double light_bounds_exit(const Light& light, const Vec3d& origin, const Vec3d& direction) {
  const auto [lo, hi] = light_eye_box(light);
  Vec3d o = origin - light.position, d = direction;
  if (light.type != LightType::omni) {
    o = light.view.transform_point(origin);
    d = light.view.transform_vector(direction);
  }
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  const double os[3] = {o.x, o.y, o.z}, ds[3] = {d.x, d.y, d.z};
  const double los[3] = {lo.x, lo.y, lo.z}, his[3] = {hi.x, hi.y, hi.z};
  for (int a = 0; a < 3; ++a) {
    if (ds[a] == 0) {
      if (os[a] < los[a] || os[a] > his[a]) return 0;
      continue;
    }
    double ta = (los[a] - os[a]) / ds[a], tb = (his[a] - os[a]) / ds[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t1 > t0 ? t1 : 0;
}

double light_reach(const RenderScene& scene) {
  const Camera& cam = scene.camera;
  const Light& light = scene.light;
  const auto light_distance = [&](const Vec3d& x) {
    return light.is_perspective() ? length(x - light.position)
                                  : dot(x - light.position, light.direction) - light.near;
  };
  double reach = 0;
  for (int row = 0; row < cam.height; ++row)
    for (int col = 0; col < cam.width; ++col) {
      const Ray ray = pixel_ray(cam, col, row);
      const double need = std::min(scene.surface[static_cast<std::size_t>(row) * cam.width + col],
                                   light_bounds_exit(light, ray.origin, ray.direction));
      if (!(need > 0)) continue;
      // Distance (and depth) from the light is convex along the ray: the ends bound it.
      reach = std::max(
          {reach, light_distance(ray.origin), light_distance(ray.origin + need * ray.direction)});
    }
  return 1.001 * reach;
}

// ---- the opacity map ----------------------------------------------------------------------------

struct GlOpacityMap::State {
  Light light;
  Medium medium;
  std::shared_ptr<const GlDensityField> field;
  OpacityMapOptions options;
  Program build;
  BufferHandle tau;
  int faces = 1;
  double range = 0;
  std::vector<Mat4d> world_to_clip;
};

GlOpacityMap::~GlOpacityMap() = default;

Result<std::unique_ptr<GlOpacityMap>> GlOpacityMap::create(
    const Light& light, const Medium& medium, const OpacityMapOptions& options, double reach,
    std::shared_ptr<const GlDensityField> field) {
  if (options.size < 2 || options.size > 1024 || options.layers < 2 || options.layers > 4096 ||
      options.substeps < 1)
    return Error{"opacity map: size must be in [2, 1024], layers in [2, 4096], got " +
                 std::to_string(options.size) + " and " + std::to_string(options.layers)};
  std::unique_ptr<GlOpacityMap> r(new GlOpacityMap());
  r->state_ = std::make_unique<State>();
  State& s = *r->state_;
  s.light = light;
  s.medium = medium;
  s.options = options;
  s.faces = light.type == LightType::omni ? 6 : 1;
  if (!field) {
    Result<std::shared_ptr<const GlDensityField>> made = GlDensityField::create(medium.density);
    if (!made) return made.error();
    field = *made;
  }
  s.field = std::move(field);
  Result<Program> build = Program::compile_compute(
      "#version 450 core\n" + std::string(kGlslDensity) + detail::kDensityGridGlsl + kOpacityBuild,
      "opacity map");
  if (!build) return build.error();
  s.build = std::move(*build);
  for (int f = 0; f < s.faces; ++f)
    s.world_to_clip.push_back(
        light.projection * (light.type == LightType::omni ? omni_face_view(light, f) : light.view));
  // The last layer's distance: the farthest frustum corner (omni: the cube's), or the depth range.
  if (light.type == LightType::directional) {
    s.range = light.far - light.near;
  } else {
    bool ok = false;
    const Mat4d inv = inverse(s.world_to_clip[0], &ok);
    LV_CHECK(ok);
    for (int k = 0; k < 4; ++k) {
      const Vec3d c = inv.transform_point({k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, 1.0});
      s.range = std::max(s.range, length(c - light.position));
    }
  }
  if (reach > 0) s.range = std::min(s.range, reach);
  const std::size_t count = static_cast<std::size_t>(s.faces) * options.size * options.size *
                            static_cast<std::size_t>(options.layers);
  s.tau = make_storage(count, nullptr);
  s.build.use();
  s.field->bind(s.build);
  glUniform1i(s.build.uniform("om_substeps"), options.substeps);
  glUniform1f(s.build.uniform("om_sigma_t"), static_cast<float>(medium.extinction()));
  r->bind(s.build);
  glUseProgram(0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: setting up the opacity map: " + e};
  return r;
}

void GlOpacityMap::update() const {
  const State& s = *state_;
  s.build.use();
  s.field->bind_texture();
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, s.tau.id());
  const GLuint groups = static_cast<GLuint>((s.options.size + 7) / 8);
  glDispatchCompute(groups, groups, static_cast<GLuint>(s.faces));
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

void GlOpacityMap::bind(const Program& program) const {
  const State& s = *state_;
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, s.tau.id());
  glUniform1i(program.uniform("om_size"), s.options.size);
  glUniform1i(program.uniform("om_layers"), s.options.layers);
  glUniform1i(program.uniform("om_faces"), s.faces);
  glUniform1i(program.uniform("om_point"), s.light.is_perspective() ? 1 : 0);
  glUniform1f(program.uniform("om_range"), static_cast<float>(s.range));
  const Vec3d p = s.light.position, d = s.light.direction;
  glUniform3f(program.uniform("om_light_position"), float(p.x), float(p.y), float(p.z));
  glUniform3f(program.uniform("om_light_direction"), float(d.x), float(d.y), float(d.z));
  glUniform1f(program.uniform("om_near"), static_cast<float>(s.light.near));
  for (int f = 0; f < s.faces; ++f) {
    bool ok = false;
    const Mat4d inv = inverse(s.world_to_clip[f], &ok);
    LV_CHECK(ok);
    set_matrix(program, "om_world_to_clip[" + std::to_string(f) + "]", s.world_to_clip[f]);
    set_matrix(program, "om_clip_to_world[" + std::to_string(f) + "]", inv);
  }
}

// ---- the in-scattering grid ---------------------------------------------------------------------

struct GlDensityGrid::State {
  DensityGridOptions options;
  std::shared_ptr<const GlDensityField> field;
  std::unique_ptr<GlOpacityMap> opacity;
  Program build;
  BufferHandle grid, columns;
  int cols_x = 0, cols_y = 0;
};

GlDensityGrid::~GlDensityGrid() = default;

Result<std::unique_ptr<GlDensityGrid>> GlDensityGrid::create(const RenderScene& scene,
                                                             const DensityGridOptions& options) {
  if (options.tile < 0 || options.tile > 256 || options.slices < 2 || options.slices > 4096 ||
      options.substeps < 1)
    return Error{
        "density grid: tile must be in [0, 256] (0: automatic), slices in [2, 4096], got " +
        std::to_string(options.tile) + " and " + std::to_string(options.slices)};
  std::unique_ptr<GlDensityGrid> r(new GlDensityGrid());
  r->state_ = std::make_unique<State>();
  State& s = *r->state_;
  s.options = options;
  const Camera& cam = scene.camera;
  const int w = cam.width, h = cam.height;
  const Light& light = scene.light;
  // What each pixel needs: its surface, or where its ray leaves the light's bounds if nearer.
  std::vector<double> need(static_cast<std::size_t>(w) * h);
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * w + col;
      const Ray ray = pixel_ray(cam, col, row);
      need[i] = std::min(scene.surface[i], light_bounds_exit(light, ray.origin, ray.direction));
    }
  s.options.tile = options.tile > 0 ? options.tile : automatic_tile(scene, options.slices);
  const int tile = s.options.tile;
  s.cols_x = (w + tile - 1) / tile;
  s.cols_y = (h + tile - 1) / tile;
  std::vector<float> t1(static_cast<std::size_t>(s.cols_x) * s.cols_y, 0.0f);
  // A point light's columns are read at the point seen from the light at the pixel's angle ψ from
  // the ray's origin (airlight.glsl's grid_column_at_angle): each column's ray, in GL coordinates.
  const bool by_angle = light.is_perspective() && tile > 1;
  std::vector<Ray> column_rays;
  if (by_angle) {
    bool ok = false;
    const Mat4d inv = inverse(cam.view.projection * cam.view.view, &ok);
    LV_CHECK(ok);
    for (int y = 0; y < s.cols_y; ++y)
      for (int x = 0; x < s.cols_x; ++x) {
        const double nx = 2.0 * (x + 0.5) * tile / w - 1;
        const double ny = (cam.view.flip_y ? -1 : 1) * (2.0 * (y + 0.5) * tile / h - 1);
        const Vec3d near = inv.transform_point({nx, ny, -1}),
                    far = inv.transform_point({nx, ny, 1});
        column_rays.push_back(
            {cam.view.is_perspective() ? cam.view.position : near, normalize(far - near)});
      }
  }
  const auto light_h = [&](const Vec3d& a, const Vec3d& dir) {
    return std::max(length(cross(dir, a)), 1e-6 * std::max(1.0, length(a)));
  };
  // Each column reaches the farthest point any pixel it is interpolated into needs (by angle: the
  // column's point at the pixel's ψ, at most twice the pixel's distance: beyond the column's last
  // angle its end).
  for (int row = 0; row < h; ++row) {
    const int gl_row = cam.view.flip_y ? row : h - 1 - row;  // GL row 0 is NDC y = −1
    for (int col = 0; col < w; ++col) {
      const double need_here = need[static_cast<std::size_t>(row) * w + col];
      if (!(need_here > 0)) continue;
      double sin_psi = 0, cos_psi = 1;
      if (by_angle) {
        const Ray ray = pixel_ray(cam, col, row);
        const Vec3d a = light.position - ray.origin;
        const double psi = std::atan2(need_here * light_h(a, ray.direction),
                                      dot(a, a) - need_here * dot(a, ray.direction));
        sin_psi = std::sin(psi);
        cos_psi = std::cos(psi);
      }
      const double qx = (col + 0.5) / tile - 0.5, qy = (gl_row + 0.5) / tile - 0.5;
      const int x0 = std::clamp(static_cast<int>(std::floor(qx)), 0, s.cols_x - 1);
      const int y0 = std::clamp(static_cast<int>(std::floor(qy)), 0, s.cols_y - 1);
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int x = std::min(x0 + dx, s.cols_x - 1), y = std::min(y0 + dy, s.cols_y - 1);
          const std::size_t c = static_cast<std::size_t>(y) * s.cols_x + x;
          double reach = need_here;
          if (by_angle) {
            const Ray& cr = column_rays[c];
            const Vec3d a = light.position - cr.origin;
            const double den = light_h(a, cr.direction) * cos_psi + dot(a, cr.direction) * sin_psi;
            const double far = 2 * need_here;
            reach = den > 0 ? std::min(far, dot(a, a) * sin_psi / den) : far;
          }
          float& t = t1[c];
          t = std::max(t, static_cast<float>(reach * (1 + 1e-6)));
        }
    }
  }
  Result<std::shared_ptr<const GlDensityField>> field =
      GlDensityField::create(scene.medium.density);
  if (!field) return field.error();
  s.field = *field;
  Result<std::unique_ptr<GlOpacityMap>> opacity =
      GlOpacityMap::create(light, scene.medium, options.opacity, light_reach(scene), s.field);
  if (!opacity) return opacity.error();
  s.opacity = std::move(*opacity);
  Result<Program> build = Program::compile_compute(compute_header() + kGlslCommon + kGlslDensity +
                                                       "#define LIGHTVOL_DENSITY_INTEGRAND\n" +
                                                       kGlslOpacityLookup + kGridBuild,
                                                   "density grid");
  if (!build) return build.error();
  s.build = std::move(*build);
  s.columns = make_storage(t1.size(), t1.data());
  s.grid = make_storage(2 * t1.size() * static_cast<std::size_t>(options.slices), nullptr);
  s.build.use();
  set_scene_uniforms(s.build, scene);
  s.field->bind(s.build);
  glUniform1i(s.build.uniform("f_table"), 1);  // declared by the common part; unused here
  glUniform1i(s.build.uniform("grid_substeps"), options.substeps);
  r->bind(s.build);
  s.opacity->bind(s.build);
  glUseProgram(0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: setting up the density grid: " + e};
  return r;
}

void GlDensityGrid::update() const {
  const State& s = *state_;
  s.opacity->update();
  s.build.use();
  s.field->bind_texture();
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, 0);
  s.opacity->bind(s.build);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, s.grid.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, s.columns.id());
  glDispatchCompute(static_cast<GLuint>((s.cols_x + 7) / 8),
                    static_cast<GLuint>((s.cols_y + 7) / 8), 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

int GlDensityGrid::tile() const { return state_->options.tile; }

void GlDensityGrid::bind(const Program& program) const {
  const State& s = *state_;
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, s.grid.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, s.columns.id());
  glUniform2i(program.uniform("grid_columns"), s.cols_x, s.cols_y);
  glUniform1i(program.uniform("grid_tile"), s.options.tile);
  glUniform1i(program.uniform("grid_slices"), s.options.slices);
}

}  // namespace lightvol
