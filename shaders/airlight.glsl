// lightvol's airlight shader: single-scattering airlight from a closed light volume (Billeter,
// Sintorn, Assarsson, HPG 2010). One file for every renderer: lightvol's OpenGL 4.5 checker
// compiles it at build time, the web viewer (WebGL2) loads it as it is. docs/engines.md describes
// its inputs (uniforms, textures, blending) for engine developers.
//
// The file has no #version line: the host prepends one, the precision statements GLSL ES needs,
// and one #define naming the stage to compile:
//   OpenGL 4.5:  "#version 450 core\n#define LIGHTVOL_<STAGE>\n"
//   WebGL2:      "#version 300 es\nprecision highp float;\nprecision highp int;\n"
//                "precision highp sampler2D;\n#define LIGHTVOL_<STAGE>\n"
// Stages:
//   LIGHTVOL_VOLUME_VERTEX, LIGHTVOL_VOLUME_FRAGMENT    pass 1: draw the volume's triangles with
//       additive float blending (ONE, ONE), no depth test, no culling, depth clamping; each
//       fragment adds (back face) or subtracts (front face) the airlight's angular part from the
//       eye to its point, clamped to the scene surface, into an RG32F target (sum, face count).
//   LIGHTVOL_RESOLVE_VERTEX, LIGHTVOL_RESOLVE_FRAGMENT  pass 2: one full-screen triangle (three
//       vertices, no attributes) turns the sums into the airlight (R32F).
//   LIGHTVOL_COMMON  only the uniforms and functions (phase functions, the spot profile, the pixel's
//       ray, the angular integral), for other passes built on them (lightvol's ray marchers).
//   LIGHTVOL_SURFACE_VERTEX, LIGHTVOL_SURFACE_FRAGMENT  for hosts without a distance buffer: draw
//       the scene with the depth test on into an R32F target cleared to 3e38; each fragment writes
//       its distance along the pixel's ray, the `surface` texture pass 1 reads.
//   LIGHTVOL_DENSITY  (with the volume and resolve fragment stages) a medium of varying density:
//       pass 1 also writes each fragment's signed D(t), read from the per-frame grid (lightvol's
//       GlDensityGrid in OpenGL 4.5, web/density.js in WebGL2), to a second target that pass 2
//       adds.
//   LIGHTVOL_LIVE_VOLUME_VERTEX  pass 1's vertex stage for a live volume (docs/engines.md): the
//       static volume of a light made from its shadow map(s) as it is drawn, with no vertex
//       attributes. Vertex gl_VertexID is vertex gl_VertexID of `lightvol build`'s static volume
//       of those maps: grid vertex row * W + col (omni: face * W * W + row * W + col) at texel
//       (col, row)'s centre ray and depth, then the closing's (spot: the apex; directional: the
//       border's near-plane copies, then the cap's centre; omni: none). Drawn with build's
//       triangles as the index buffer, with LIGHTVOL_VOLUME_FRAGMENT.
//   LIGHTVOL_LIVE_COMMON  only the live stage's uniforms and functions (a texel's grid point, the
//       border ring), for the adaptive live volume's compute passes (shaders/live_adaptive.comp).

#if defined(LIGHTVOL_VOLUME_VERTEX) || defined(LIGHTVOL_SURFACE_VERTEX)
layout(location = 0) in vec3 position;
uniform mat4 view_projection;
out vec3 world;
void main() {
  world = position;
  gl_Position = view_projection * vec4(position, 1.0);
}
#endif

#if defined(LIGHTVOL_LIVE_VOLUME_VERTEX) || defined(LIGHTVOL_LIVE_COMMON)
// The shadow maps as the light's projection rendered them: texture row t (t = 0 at the bottom)
// holds NDC y = -1 + 2(t + 1/2)/H. Depth textures (compare mode off) or R32F, read with texelFetch.
// Spot and directional lights use shadow_maps[0]; omni lights the six faces +X -X +Y -Y +Z -Z.
uniform sampler2D shadow_maps[6];
uniform ivec2 live_size;       // W, H (of each face)
#ifdef LIGHTVOL_LIVE_TYPE
// The web addon: its maps are window depth, not flipped, and one program draws one light type,
// so these are constants (branches a SIMD rasterizer need not run for every vertex).
const int live_flip_y = 0;
const int live_depth = 0;
const int live_type = LIGHTVOL_LIVE_TYPE;
#else
uniform int live_flip_y;       // the light's flip_y: image row 0 is NDC y = -1
uniform int live_depth;        // 0 window depth, 1 linear (eye -z), 2 radial (distance to the eye)
uniform int live_type;         // 0 spot (closed by a fan to the apex), 1 directional (walls and a
                               // cap), 2 omni (six faces joined by seams and corners)
#endif
uniform int live_standard;     // 1 when the border ring runs top, right, bottom, left; 0 reversed
uniform float live_min_t;      // the smallest parameter along a texel's near-far segment
// A texel's near and far points in the light's eye space, homogeneous and affine in its NDC
// (x, y): ray_x * x + ray_y * y + near_0 (far_0). Window depth d blends them without cancellation:
// (1 - d) near + d far, homogeneous.
uniform vec4 live_ray_x;
uniform vec4 live_ray_y;
uniform vec4 live_near_0;
uniform vec4 live_far_0;
uniform mat4 live_eye_to_world[6];  // the light's (omni: each face's) eye to world
uniform vec3 live_apex;        // world: the spot's apex
uniform vec3 live_cap;         // world: the directional cap's centre

vec2 live_ndc(ivec2 texel) {
  vec2 t = (2.0 * vec2(texel) + 1.0) / vec2(live_size) - 1.0;
  return vec2(t.x, live_flip_y == 1 ? t.y : -t.y);
}

// Texel (col, row)'s point at parameter t of its near-far segment (eye space).
vec3 live_segment(vec2 ndc, float t) {
  vec4 base = live_ray_x * ndc.x + live_ray_y * ndc.y;
  vec3 pn = (base + live_near_0).xyz / (base + live_near_0).w;
  vec3 pf = (base + live_far_0).xyz / (base + live_far_0).w;
  return pn + t * (pf - pn);
}

// The stored depth of face f's texel t (samplers are indexed by constants only). With
// LIGHTVOL_LIVE_ONE_MAP defined (the web addon's spot and directional volumes) shadow_maps[0]
// only: a SIMD rasterizer may run all six fetches below for every vertex.
float live_fetch(int f, ivec2 t) {
#ifdef LIGHTVOL_LIVE_ONE_MAP
  return texelFetch(shadow_maps[0], t, 0).r;
#else
  if (f == 0) return texelFetch(shadow_maps[0], t, 0).r;
  if (f == 1) return texelFetch(shadow_maps[1], t, 0).r;
  if (f == 2) return texelFetch(shadow_maps[2], t, 0).r;
  if (f == 3) return texelFetch(shadow_maps[3], t, 0).r;
  if (f == 4) return texelFetch(shadow_maps[4], t, 0).r;
  return texelFetch(shadow_maps[5], t, 0).r;
#endif
}

// Face f's texel (col, row)'s grid vertex (eye space), as lightvol's Unprojector places it.
vec3 live_grid_point(int f, ivec2 texel) {
  int row = live_flip_y == 1 ? texel.y : live_size.y - 1 - texel.y;
  float d = live_fetch(f, ivec2(texel.x, row));
  vec2 ndc = live_ndc(texel);
  vec4 base = live_ray_x * ndc.x + live_ray_y * ndc.y;
  // A NaN texel (which build refuses) gives the texel's near-plane point: no light where the
  // depth is unknown. Other depths clamp to the near and far planes.
  bool unknown = isnan(d);
  if (live_depth == 0) {
    float w = unknown ? live_min_t : clamp(d, live_min_t, 1.0);
    vec4 h = base + ((1.0 - w) * live_near_0 + w * live_far_0);
    return h.xyz / h.w;
  }
  vec3 pn = (base + live_near_0).xyz / (base + live_near_0).w;
  vec3 pf = (base + live_far_0).xyz / (base + live_far_0).w;
  vec3 dv = pf - pn;
  float t = 0.0;
  if (live_depth == 1) {
    t = (-d - pn.z) / dv.z;
  } else {
    // |pn + t dv| = d, the far root; a depth no ray reaches gives the near point.
    float a = dot(dv, dv), half_b = dot(pn, dv), c = dot(pn, pn) - d * d;
    float disc = half_b * half_b - a * c;
    t = disc < 0.0 ? 0.0 : (-half_b + sqrt(disc)) / a;
  }
  return pn + (unknown ? live_min_t : clamp(t, live_min_t, 1.0)) * dv;
}

// Texel of ring vertex k (build's border ring: top row left to right, right column down, bottom
// row right to left, left column up; reversed when live_standard is 0).
ivec2 live_ring_texel(int k) {
  int w1 = live_size.x - 1, h1 = live_size.y - 1;
  if (live_standard == 0) k = 2 * (w1 + h1) - 1 - k;
  if (k < w1) return ivec2(k, 0);
  k -= w1;
  if (k < h1) return ivec2(w1, k);
  k -= h1;
  if (k < w1) return ivec2(w1 - k, h1);
  return ivec2(0, h1 - (k - w1));
}

#endif

#ifdef LIGHTVOL_LIVE_VOLUME_VERTEX
uniform mat4 view_projection;
out vec3 world;
// With LIGHTVOL_LIVE_PITCH defined (the web addon), grid vertex ids run live_pitch >= W a row:
// vertex row * live_pitch + col (omni: face * live_pitch * W + ...), the ids of columns W and up
// unused, the closing's after the grid's, so that the rows' ids need not be W apart (a rasterizer
// whose vertex cache is direct-mapped by id, SwiftShader's, reuses nothing when W is a multiple of
// its size). Without it, live_pitch is W: build's numbering.
#ifdef LIGHTVOL_LIVE_PITCH
uniform int live_pitch;
#else
#define live_pitch live_size.x
#endif
void main() {
  int texels = live_pitch * live_size.y;
  int v = gl_VertexID;
  if (v < (live_type == 2 ? 6 * texels : texels)) {
    int f = v / texels;
    int i = v - f * texels;
    vec3 eye = live_grid_point(f, ivec2(i % live_pitch, i / live_pitch));
#ifdef LIGHTVOL_LIVE_ONE_MAP
    world = (live_eye_to_world[0] * vec4(eye, 1.0)).xyz;
#else
    world = (live_eye_to_world[f] * vec4(eye, 1.0)).xyz;
#endif
  } else if (live_type == 0) {
    world = live_apex;
  } else {
    int k = v - texels;
    if (k == 2 * (live_size.x - 1) + 2 * (live_size.y - 1)) {
      world = live_cap;
    } else {
      vec3 eye = live_segment(live_ndc(live_ring_texel(k)), 0.0);
      world = (live_eye_to_world[0] * vec4(eye, 1.0)).xyz;
    }
  }
  gl_Position = view_projection * vec4(world, 1.0);
}
#endif

#ifdef LIGHTVOL_RESOLVE_VERTEX
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
#endif

#if defined(LIGHTVOL_COMMON) || defined(LIGHTVOL_VOLUME_FRAGMENT) || defined(LIGHTVOL_RESOLVE_FRAGMENT) || defined(LIGHTVOL_SURFACE_FRAGMENT)
const float PI = 3.14159265358979;
const float HALF_PI_BELOW = 1.5707960;  // largest float below pi/2: tan stays positive

uniform mat4 inv_projection;   // camera clip -> camera eye
uniform mat3 eye_to_world;     // camera eye -> world rotation
uniform vec3 camera_position;  // world: the eye (perspective) or the eye-space origin (ortho)
uniform int perspective;
uniform vec2 viewport;
uniform int flip_y;

uniform int light_type;        // 0 point (spot, omni), 1 directional
uniform vec3 light_position;
uniform vec3 light_direction;
uniform float light_near;
uniform float sigma_s;
uniform float sigma_t;
uniform float intensity;
uniform int phase_type;        // 0 isotropic, 1 Henyey-Greenstein, 2 Schlick
uniform float phase_param;     // g or k

uniform sampler2D f_table;
uniform float f_u_max;

uniform int profile_enabled;   // soft-edged spot, docs/design.md 6: smoothstep(cos outer, cos inner, cos alpha)
uniform float profile_cos_inner;
uniform float profile_cos_outer;

// The current ray, set by point_setup(), for integrands that depend on the point x(xi).
vec3 g_origin;
vec3 g_dir;
float g_h;
float g_s0;

float profile(vec3 to_x) {
  if (profile_enabled == 0) return 1.0;
  return smoothstep(profile_cos_outer, profile_cos_inner, dot(normalize(to_x), light_direction));
}

// The world-space ray of this fragment's pixel centre.
void pixel_ray(out vec3 origin, out vec3 dir) {
  vec2 ndc = 2.0 * gl_FragCoord.xy / viewport - 1.0;
  if (flip_y == 1) ndc.y = -ndc.y;
  vec4 n = inv_projection * vec4(ndc, -1.0, 1.0);
  vec3 near_eye = n.xyz / n.w;
  if (perspective == 1) {
    origin = camera_position;
    dir = normalize(eye_to_world * near_eye);
  } else {
    origin = camera_position + eye_to_world * near_eye;
    dir = normalize(eye_to_world * vec3(0.0, 0.0, -1.0));
  }
}

float phase(float c) {
  const float inv4pi = 1.0 / (4.0 * PI);
  if (phase_type == 1) {
    float g = phase_param;
    float d = 1.0 + g * g - 2.0 * g * c;
    return inv4pi * (1.0 - g * g) / (d * sqrt(d));
  }
  if (phase_type == 2) {
    float k = phase_param;
    float d = 1.0 - k * c;
    return inv4pi * (1.0 - k * k) / (d * d);
  }
  return inv4pi;
}

// Point light seen along a ray: distance h of the light from the ray's line, parameter s0 of the
// closest point, and the Sun et al. optical thickness u = sigma_t * h.
void point_setup(vec3 origin, vec3 dir, out float h, out float s0) {
  vec3 to_light = light_position - origin;
  s0 = dot(to_light, dir);
  h = max(length(cross(dir, to_light)), 1e-6 * max(1.0, length(to_light)));
  g_origin = origin;
  g_dir = dir;
  g_h = h;
  g_s0 = s0;
}

const float GL_X[4] = float[4](0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                               0.9602898564975363);
const float GL_W[4] = float[4](0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                               0.1012285362903763);

float integrand(float xi, float u) {
  float f = phase(cos(2.0 * xi)) * exp(-u * tan(xi));
  if (profile_enabled == 1) {
    float s = g_s0 - g_h / tan(2.0 * xi);  // the point x(xi) on the ray
    f *= profile(g_origin + s * g_dir - light_position);
  }
  return f;
}

// integral from a to b of p(cos 2xi)*exp(-u tan xi) dxi, `panels` 8-point Gauss-Legendre panels.
float quadrature(float a, float b, float u, int panels) {
  a = min(a, HALF_PI_BELOW);
  b = min(b, HALF_PI_BELOW);
  float width = (b - a) / float(panels);
  float half_width = 0.5 * width;
  float sum = 0.0;
  for (int p = 0; p < panels; ++p) {
    float mid = a + (float(p) + 0.5) * width;
    for (int i = 0; i < 4; ++i) {
      float dx = half_width * GL_X[i];
      sum += GL_W[i] * (integrand(mid - dx, u) + integrand(mid + dx, u));
    }
  }
  return sum * half_width;
}

// Sun et al.'s F(u, v) from the table: bilinear with float weights (texelFetch, no filtering).
float sun_f(float u, float v) {
  ivec2 size = textureSize(f_table, 0);
  vec2 p = vec2(clamp(v, 0.0, 0.5 * PI) / (0.5 * PI) * float(size.x - 1),
                sqrt(u / f_u_max) * float(size.y - 1));
  ivec2 i = min(ivec2(p), size - 2);
  vec2 f = p - vec2(i);
  float f00 = texelFetch(f_table, i, 0).r;
  float f10 = texelFetch(f_table, i + ivec2(1, 0), 0).r;
  float f01 = texelFetch(f_table, i + ivec2(0, 1), 0).r;
  float f11 = texelFetch(f_table, i + ivec2(1, 1), 0).r;
  return mix(mix(f00, f10, f.x), mix(f01, f11, f.x), f.y);
}

float angular_integral(float a, float b, float u, int panels) {
  if (phase_type == 0 && u <= f_u_max && profile_enabled == 0) return (sun_f(u, b) - sun_f(u, a)) * (1.0 / (4.0 * PI));
  return quadrature(a, b, u, panels);
}

// The in-scattering grid of a medium of varying density (docs/design.md 6) spaces its slices
// along a column's ray uniformly in grid_coordinate, which its builders (density_grid.glsl's
// grid_node) and its readers (LIGHTVOL_DENSITY below) share.
// A ray's distance to the point light, a the vector from the ray's origin to the light.
float grid_light_h(vec3 a, vec3 dir) { return max(length(cross(dir, a)), 1e-6 * max(1.0, length(a))); }
// The angle at the point light between the ray's origin and its point at distance t: by the law of
// sines atan2(t h, |a|^2 - t s0), s0 = a . dir; d psi / dt = h / d^2, the in-scattering's peak.
float grid_light_angle(vec3 a, vec3 dir, float t) {
  return atan(t * grid_light_h(a, dir), dot(a, a) - t * dot(a, dir));
}
// Where the point at distance t (at angle psi from the light) lies along a column reaching t1
// (angle psi1), in [0, 1]: t / t1 for a directional light; for a point light the mean of t / t1
// and psi / psi1, so that slices are dense where the ray passes the light (no slice longer than
// twice either uniform spacing: uniform in t where the density and the eye-side transmittance
// vary, in angle across the 1/d^2 peak).
float grid_coordinate(float t, float psi, float t1, float psi1) {
  float w = light_type == 1 || !(psi1 > 0.0) ? t / t1 : 0.5 * (t / t1 + psi / psi1);
  return clamp(w, 0.0, 1.0);
}
#endif

#ifdef LIGHTVOL_VOLUME_FRAGMENT
in vec3 world;
layout(location = 0) out vec2 result;  // (signed angular integral, signed fragment count)
uniform sampler2D surface;
uniform int baseline;
uniform int panels;
uniform float facing_sign;
#ifdef LIGHTVOL_DENSITY
// Media of varying density (docs/design.md 6): a per-frame grid of columns, one per grid_tile x
// grid_tile pixels, each holding D = F - F_hom and dD/dw at grid_slices points along the column's
// ray uniform in w = grid_coordinate (above: the distance for a directional light; for a point
// light a blend of the distance and the angle at the light, so that slices are dense where the
// ray passes the light), w from 0 at the eye to 1 at t1 of the column: the heterogeneous
// cumulative in-scattering along the column's ray minus the homogeneous one that this fragment
// computes exactly; for a point light times h, the column ray's distance to the light
// (density_grid.glsl's grid_ray_scale). Each fragment adds its signed D (bilinear across columns,
// cubic Hermite across slices) to a second target. Across columns a point light's D is matched by
// angle, not by distance: each column is read at its point seen from the light at the same angle
// psi from the ray's origin as the fragment's point (half of which is xi - xi0 of the closed
// form), and the sum divided by the fragment's own h, so that what is interpolated varies slowly
// even for rays passing close to the light. OpenGL 4.5 (lightvol's GlDensityGrid) keeps the grid
// in shader storage buffers; WebGL2 (the web viewer's web/density.js, GL_ES) in textures:
// grid_texture RG32F (D, dD/dw) at (column x, column y, slice), grid_reach R32F t1 at (column x,
// column y).
uniform ivec2 grid_columns;
uniform int grid_tile;
uniform int grid_slices;
#ifdef GL_ES
uniform highp sampler3D grid_texture;
uniform highp sampler2D grid_reach;
float grid_t1(ivec2 c) { return texelFetch(grid_reach, c, 0).r; }
vec2 grid_d(ivec2 c, int k) { return texelFetch(grid_texture, ivec3(c, k), 0).rg; }
#else
layout(std430, binding = 4) readonly buffer DensityGrid { vec2 grid_d_buffer[]; };
layout(std430, binding = 5) readonly buffer DensityColumns { float grid_t1_buffer[]; };
float grid_t1(ivec2 c) { return grid_t1_buffer[c.y * grid_columns.x + c.x]; }
vec2 grid_d(ivec2 c, int k) { return grid_d_buffer[(c.y * grid_columns.x + c.x) * grid_slices + k]; }
#endif
layout(location = 1) out float varying_part;
// Column c's D at grid coordinate w (its slices are uniform in w, storing D and dD/dw): cubic
// Hermite.
float grid_column(ivec2 c, float w) {
  float k = w * float(grid_slices - 1);
  int k0 = clamp(int(k), 0, grid_slices - 2);
  vec2 a = grid_d(c, k0);
  vec2 b = grid_d(c, k0 + 1);
  float u = k - float(k0), h = 1.0 / float(grid_slices - 1);
  float u2 = u * u, u3 = u2 * u;
  return (2.0 * u3 - 3.0 * u2 + 1.0) * a.x + (u3 - 2.0 * u2 + u) * h * a.y +
         (3.0 * u2 - 2.0 * u3) * b.x + (u3 - u2) * h * b.y;
}
// Column c's D at distance t of its own ray, at angle psi from a point light (a the vector from
// the ray's origin to the light).
float grid_column_at(ivec2 c, float t, float psi, vec3 a, vec3 dir) {
  float t1 = grid_t1(c);
  if (!(t1 > 0.0)) return 0.0;
  float psi1 = light_type == 1 ? 0.0 : grid_light_angle(a, dir, t1);
  return grid_column(c, grid_coordinate(t, psi, t1, psi1));
}
// Column c's value at its point seen from the light at angle psi (sin, cos) from its ray's origin:
// by the law of sines, t = |a|^2 sin psi / (h cos psi + s0 sin psi), a the origin-to-light vector,
// s0 = a . dir; beyond the ray's last angle (the denominator <= 0) its end.
float grid_column_at_angle(ivec2 c, float psi, float sin_psi, float cos_psi) {
  vec2 ndc = 2.0 * (vec2(c) + 0.5) * float(grid_tile) / viewport - 1.0;
  if (flip_y == 1) ndc.y = -ndc.y;
  vec4 n = inv_projection * vec4(ndc, -1.0, 1.0);
  vec3 near_eye = n.xyz / n.w;
  vec3 origin = perspective == 1 ? camera_position : camera_position + eye_to_world * near_eye;
  vec3 dir = normalize(eye_to_world * (perspective == 1 ? near_eye : vec3(0.0, 0.0, -1.0)));
  vec3 a = light_position - origin;
  float den = grid_light_h(a, dir) * cos_psi + dot(a, dir) * sin_psi;
  if (!(den > 0.0)) return grid_t1(c) > 0.0 ? grid_column(c, 1.0) : 0.0;
  return grid_column_at(c, dot(a, a) * sin_psi / den, psi, a, dir);
}
float grid_lookup(float t, vec3 origin, vec3 dir) {
  vec2 q = clamp(gl_FragCoord.xy / float(grid_tile) - 0.5, vec2(0.0), vec2(grid_columns - 1));
  ivec2 i = ivec2(q);
  vec3 a = light_position - origin;
  float psi = light_type == 1 ? 0.0 : grid_light_angle(a, dir, t);
  float scale = light_type == 1 ? 1.0 : 1.0 / grid_light_h(a, dir);
  // One pixel per column: the pixel's own column (its ray) at its own t.
  if (grid_tile == 1) return grid_column_at(i, t, psi, a, dir) * scale;
  ivec2 j = min(i + 1, grid_columns - 1);
  vec2 f = q - vec2(i);
  float d00, d10, d01, d11;
  if (light_type == 1) {  // directional: by distance
    d00 = grid_column_at(i, t, 0.0, a, dir);
    d10 = grid_column_at(ivec2(j.x, i.y), t, 0.0, a, dir);
    d01 = grid_column_at(ivec2(i.x, j.y), t, 0.0, a, dir);
    d11 = grid_column_at(j, t, 0.0, a, dir);
  } else {
    float sp = sin(psi), cp = cos(psi);
    d00 = grid_column_at_angle(i, psi, sp, cp);
    d10 = grid_column_at_angle(ivec2(j.x, i.y), psi, sp, cp);
    d01 = grid_column_at_angle(ivec2(i.x, j.y), psi, sp, cp);
    d11 = grid_column_at_angle(j, psi, sp, cp);
  }
  float y0 = d00 + f.x * (d10 - d00);
  float y1 = d01 + f.x * (d11 - d01);
  return (y0 + f.y * (y1 - y0)) * scale;
}
#endif
void main() {
  vec3 origin, dir;
  pixel_ray(origin, dir);
  float t_surface = texelFetch(surface, ivec2(gl_FragCoord.xy), 0).r;
  float t = clamp(dot(world - origin, dir), 0.0, t_surface);
  float s = (gl_FrontFacing ? -1.0 : 1.0) * facing_sign;
#ifdef LIGHTVOL_DENSITY
  varying_part = s * grid_lookup(t, origin, dir);
#endif
  if (light_type == 1) {
    float rate = sigma_t * (1.0 + dot(dir, light_direction));
    float x = rate * t;
    float v = abs(x) < 1e-3 ? t * (1.0 - 0.5 * x + x * x / 6.0) : (1.0 - exp(-x)) / rate;
    result = vec2(s * v, s);
    return;
  }
  float h, s0;
  point_setup(origin, dir, h, s0);
  float xi = 0.25 * PI + 0.5 * atan((t - s0) / h);
  float from = baseline == 1 ? 0.25 * PI : 0.5 * atan(h, s0);
  result = vec2(s * angular_integral(from, xi, sigma_t * h, panels), s);
}
#endif

#ifdef LIGHTVOL_RESOLVE_FRAGMENT
layout(location = 0) out float airlight;
uniform sampler2D accumulated;
uniform int baseline;
#ifdef LIGHTVOL_DENSITY
uniform sampler2D accumulated_density;  // the volume pass's signed sum of D(t)
#endif
void main() {
  vec2 a = texelFetch(accumulated, ivec2(gl_FragCoord.xy), 0).rg;
  vec3 origin, dir;
  pixel_ray(origin, dir);
  if (light_type == 1) {
    float k = dot(dir, light_direction);
    float z = dot(origin - light_position, light_direction) - light_near;
    airlight = sigma_s * intensity * phase(-k) * exp(-sigma_t * z) * a.r;
#ifdef LIGHTVOL_DENSITY
    airlight += texelFetch(accumulated_density, ivec2(gl_FragCoord.xy), 0).r;
#endif
    return;
  }
  float h, s0;
  point_setup(origin, dir, h, s0);
  float c = 2.0 * sigma_s * intensity * exp(-sigma_t * s0) / h;
  float base = 0.0;
  if (baseline == 1 && a.g != 0.0)
    base = angular_integral(0.5 * atan(h, s0), 0.25 * PI, sigma_t * h, profile_enabled == 1 ? 32 : 8);
  airlight = c * (a.r + a.g * base);
#ifdef LIGHTVOL_DENSITY
  airlight += texelFetch(accumulated_density, ivec2(gl_FragCoord.xy), 0).r;
#endif
}
#endif

#ifdef LIGHTVOL_SURFACE_FRAGMENT
in vec3 world;
layout(location = 0) out float distance_along_ray;
void main() {
  vec3 origin, dir;
  pixel_ray(origin, dir);
  distance_along_ray = dot(world - origin, dir);
}
#endif
