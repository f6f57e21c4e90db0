// lightvol's density field for heterogeneous media: the GLSL twin of src/lightvol/airlight/
// density.cpp (docs/design.md §6, "Media of varying density"), the same integer-hashed fBm of value
// noise, in float. No #version line: hosts prepend it (GLSL 4.50 or GLSL ES 3.00 with highp).
//
//   density(x) = max(0, density_offset + density_scale * fbm(x)), or 1 when density_type is 0, or
//   a voxel grid's value, trilinear in its index space (voxel centres at integers; the background
//   outside its box), when density_type is 2.

uniform int density_type;          // 0 constant (rho = 1), 1 noise, 2 voxel grid
uniform uint density_seed;
uniform float density_frequency;
uniform int density_octaves;
uniform float density_lacunarity;
uniform float density_gain;
uniform float density_offset;
uniform float density_scale;

uint density_lowbias32(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

float density_lattice(uint seed, uvec3 i) {
  uint h = density_lowbias32(seed ^ (i.x * 0x8da6b343u) ^ (i.y * 0xd8163841u) ^ (i.z * 0xcb1ab31fu));
  return float(h >> 8) * (1.0 / 8388608.0) - 1.0;
}

float value_noise(vec3 p, uint seed) {
  vec3 fl = floor(p);
  uvec3 i = uvec3(ivec3(fl));
  vec3 f = p - fl;
  vec3 u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
  float c[4];
  for (int k = 0; k < 4; ++k) {
    uvec3 j = i + uvec3(0u, uint(k & 1), uint(k >> 1));
    float a = density_lattice(seed, j);
    float b = density_lattice(seed, j + uvec3(1u, 0u, 0u));
    c[k] = a + u.x * (b - a);
  }
  float c00 = c[0], c01 = c[1], c10 = c[2], c11 = c[3];
  float y0 = c00 + u.y * (c01 - c00);
  float y1 = c10 + u.y * (c11 - c10);
  return y0 + u.z * (y1 - y0);
}

float noise_fbm(vec3 x) {
  float sum = 0.0, norm = 0.0, amplitude = 1.0, frequency = density_frequency;
  uint seed = density_seed;
  for (int o = 0; o < density_octaves; ++o) {
    sum += amplitude * value_noise(x * frequency, seed);
    norm += amplitude;
    amplitude *= density_gain;
    frequency *= density_lacunarity;
    seed += 0x9e3779b9u;
  }
  return sum / norm;
}

// The voxel grid: R32F texels fetched one by one (the filtering is ours, in float, as the C++ one).
// Not under GL_ES: the web viewer reads no grids (web/density.js refuses "vdb"), and a sampler left
// on unit 0 beside a 2D one there would fail its draws.
#ifndef GL_ES
uniform highp sampler3D density_grid;
uniform mat4 density_world_to_texel;  // the grid's world-to-index map, less its box's first index
uniform vec3 density_grid_size;         // voxels along each axis
uniform float density_grid_background;

float density_voxel(ivec3 i) {
  if (any(lessThan(i, ivec3(0))) || any(greaterThanEqual(i, ivec3(density_grid_size))))
    return density_grid_background;
  return texelFetch(density_grid, i, 0).r;
}

float grid_density(vec3 x) {
  vec3 p = (density_world_to_texel * vec4(x, 1.0)).xyz;
  vec3 fl = floor(p);
  if (any(lessThan(fl, vec3(-1.0))) || any(greaterThan(fl, density_grid_size)))
    return density_grid_background;
  ivec3 i = ivec3(fl);
  vec3 u = p - fl;
  float c[4];
  for (int k = 0; k < 4; ++k) {
    ivec3 j = i + ivec3(0, k & 1, k >> 1);
    float a = density_voxel(j);
    float b = density_voxel(j + ivec3(1, 0, 0));
    c[k] = a + u.x * (b - a);
  }
  float y0 = c[0] + u.y * (c[1] - c[0]);
  float y1 = c[2] + u.y * (c[3] - c[2]);
  return y0 + u.z * (y1 - y0);
}
#else
float grid_density(vec3 x) { return 1.0; }
#endif

float density(vec3 x) {
  if (density_type == 0) return 1.0;
  if (density_type == 2) return grid_density(x);
  return max(0.0, density_offset + density_scale * noise_fbm(x));
}
