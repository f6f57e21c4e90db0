// lightvol's per-frame grids for media of varying density (docs/design.md §6): the opacity map's
// uniforms and look-up, and the integrand of the in-scattering grid D = F - F_hom. One file for
// lightvol's OpenGL 4.5 renderer (src/lightvol/render/gl_density.cpp, compute shaders, the maps in
// shader storage buffers) and the web viewer (web/density.js, WebGL2 fragment passes, the maps in
// 3D textures). No #version line. Comes after shaders/density.glsl (density()) and, with
// LIGHTVOL_DENSITY_INTEGRAND, after airlight.glsl's common part (phase(), profile(), the light and
// medium uniforms). The host defines, before this file:
//   LIGHTVOL_OPACITY_LOOKUP      light_optical_depth(x); the host also defines the macro
//                                om_fetch(face, c, r, k): tau at column (c, r) of `face`, layer k
//   LIGHTVOL_DENSITY_INTEGRAND   d_integrand(t, rho, tau_e) along the ray g_ray_origin + t g_ray_dir,
//                                scaled by grid_ray_scale() (what the in-scattering grid stores),
//                                and the distances of the grid's slices along it (grid_node)
// Without either, only the opacity map's uniforms (for the pass that makes the map).

uniform int om_size;            // columns per face side
uniform int om_layers;          // samples along a column
uniform int om_faces;           // 1, or 6 for an omni light
uniform int om_point;           // 1 spot or omni (columns from the light), 0 directional
uniform float om_range;         // distance (directional: depth below the near plane) of the last layer
uniform vec3 om_light_position;
uniform vec3 om_light_direction;
uniform float om_near;
uniform mat4 om_world_to_clip[6];
uniform mat4 om_clip_to_world[6];

#ifdef LIGHTVOL_OPACITY_LOOKUP
// tau_L(x) = sigma_t * integral of the density along the light's path to x.
float light_optical_depth(vec3 x) {
  int face = 0;
  if (om_faces == 6) {
    vec3 d = x - om_light_position;
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) face = d.x > 0.0 ? 0 : 1;
    else if (a.y >= a.z) face = d.y > 0.0 ? 2 : 3;
    else face = d.z > 0.0 ? 4 : 5;
  }
  vec4 c = om_world_to_clip[face] * vec4(x, 1.0);
  vec2 ndc = c.xy / max(c.w, 1e-30);
  float r = om_point == 1 ? length(x - om_light_position)
                          : dot(x - om_light_position, om_light_direction) - om_near;
  vec3 g = vec3(clamp((ndc + 1.0) * 0.5 * float(om_size) - 0.5, 0.0, float(om_size - 1)),
                clamp(r / om_range * float(om_layers - 1), 0.0, float(om_layers - 1)));
  ivec3 i = min(ivec3(g), ivec3(om_size - 2, om_size - 2, om_layers - 2));
  vec3 f = g - vec3(i);
  float v[4];
  for (int k = 0; k < 4; ++k) {
    int cc = i.x + (k & 1), rr = i.y + (k >> 1);
    float a = om_fetch(face, cc, rr, i.z), b = om_fetch(face, cc, rr, i.z + 1);
    v[k] = a + f.z * (b - a);
  }
  float y0 = v[0] + f.x * (v[1] - v[0]);
  float y1 = v[2] + f.x * (v[3] - v[2]);
  return y0 + f.y * (y1 - y0);
}
#endif

#ifdef LIGHTVOL_DENSITY_INTEGRAND
vec3 g_ray_origin;
vec3 g_ray_dir;
// What the grid stores is D times this factor of the column's ray: for a point light h, the ray's
// distance to the light (so that the 1/h of F's angular form, steep across rays passing near the
// light, is not interpolated across columns: airlight.glsl's grid_lookup divides each fragment's
// look-up by its own h); 1 for a directional light. The same expression as grid_lookup's.
float grid_ray_scale() {
  if (light_type == 1) return 1.0;
  return grid_light_h(light_position - g_ray_origin, g_ray_dir);
}
// The column's slices are uniform in airlight.glsl's grid_coordinate w (from 0 at the eye to 1 at
// t1, psi1 the angle at the light there). dw/dt at distance t:
float grid_coordinate_rate(float t, float t1, float psi1) {
  if (light_type == 1 || !(psi1 > 0.0)) return 1.0 / t1;
  vec3 a = light_position - g_ray_origin;
  float h = grid_light_h(a, g_ray_dir);
  vec3 x = a - t * g_ray_dir;
  return 0.5 * (1.0 / t1 + h / max(dot(x, x), h * h) / psi1);
}
// The distance t in [t_lo, t1] where w = grid_coordinate(t) (w increases with t; t_lo is at or
// below it): Newton's method, bisecting whenever a step leaves the bracket.
float grid_node(float w, float t_lo, float t1, float psi1) {
  if (w >= 1.0) return t1;
  if (light_type == 1 || !(psi1 > 0.0)) return w * t1;
  vec3 a = light_position - g_ray_origin;
  float lo = t_lo, hi = t1, t = t_lo;
  for (int i = 0; i < 60; ++i) {
    float f = grid_coordinate(t, grid_light_angle(a, g_ray_dir, t), t1, psi1) - w;
    if (abs(f) < 1e-6) break;
    if (f < 0.0) lo = t;
    else hi = t;
    float next = t - f / grid_coordinate_rate(t, t1, psi1);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (next == t || hi - lo <= 1e-7 * t) break;
    t = next;
  }
  return t;
}
// The integrand of D at distance t, times grid_ray_scale(): (heterogeneous - homogeneous)
// in-scattering, given the density there and the eye-side optical depth up to it.
float d_integrand(float t, float rho, float tau_e) {
  vec3 x = g_ray_origin + t * g_ray_dir;
  float light_part, hom_depth;
  if (light_type == 1) {
    light_part = sigma_s * intensity * phase(-dot(g_ray_dir, light_direction));
    // Clamped as the opacity map clamps, so that D stays 0 where the density is constant.
    hom_depth = clamp(dot(x - light_position, light_direction) - light_near, 0.0, om_range);
  } else {
    vec3 to_x = x - light_position;
    float dist = length(to_x);
    light_part = sigma_s * intensity * phase(dot(to_x / dist, -g_ray_dir)) * profile(to_x) /
                 (dist * dist);
    hom_depth = min(dist, om_range);
  }
  float het = rho * exp(-light_optical_depth(x) - tau_e);
  float hom = exp(-sigma_t * (hom_depth + t));
  return light_part * (het - hom) * grid_ray_scale();
}
#endif
