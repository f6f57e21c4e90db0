// lightvol's density field for heterogeneous media: the GLSL twin of src/lightvol/airlight/
// density.cpp (docs/design.md §6, "Media of varying density"), the same integer-hashed fBm of value
// noise, in float. No #version line: hosts prepend it (GLSL 4.50 or GLSL ES 3.00 with highp).
//
//   density(x) = max(0, density_offset + density_scale * fbm(x)), or 1 when density_type is 0.

uniform int density_type;          // 0 constant (rho = 1), 1 noise
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

float density(vec3 x) {
  if (density_type == 0) return 1.0;
  return max(0.0, density_offset + density_scale * noise_fbm(x));
}
