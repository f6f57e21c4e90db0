// Media of varying density in WebGL2 (docs/design.md §6, docs/web.md): what
// src/lightvol/render/gl_density.cpp does with compute shaders, done with fragment passes that
// render into the layers of 3D textures. Per frame:
//   - the opacity map: the light-side optical depth τ_L = σt ∫ρ along the light's rays, `size`²
//     columns per face (omni: six) by `layers` samples uniform in the distance from the light
//     (directional: the depth below its near plane), cumulative: one pass per layer carries the
//     running sum in a 2D target and copies it into that layer of an R32F 3D texture;
//   - the in-scattering grid: per column of `tile`×`tile` pixels, D(t) = F(t) − F_hom(t) and its
//     derivative (for a point light times the column ray's distance to the light) at `slices`
//     distances on [0, t1] uniform in airlight.glsl's grid_coordinate (a point light's: a blend of
//     the distance and the angle at the light), t1 the farthest any pixel interpolated from the column needs
//     (its surface, or where its ray leaves the light's bounds; for a point light the column's
//     point at the pixel's angle from the light): one pass per
//     slice carries (D, eye-side optical depth, t) and writes (D, dD/dw) into an RG32F 3D texture, which
//     shaders/airlight.glsl's LIGHTVOL_DENSITY stage reads (its GL_ES branch).
// The density ρ(x) is shaders/density.glsl and the opacity map's look-up and the integrand of D
// shaders/density_grid.glsl, the files lightvol's OpenGL renderer compiles (fetched, never
// copied); the ray and phase function are airlight.glsl's LIGHTVOL_COMMON part. Defaults as `lightvol render --method volume`:
// 128 slices of 2 substeps, an opacity map of 64² × 64 layers of 4 substeps, the automatic tile.
import * as THREE from 'three';
import { lookAt, stageSource } from './airlight.js';

// ---- the medium's "density" (as parse_density in src/lightvol/airlight/airlight.cpp) ----------

const NOISE_KEYS = {
  seed: [0, 4294967295, true, 'an integer in [0, 4294967295]', 0],
  frequency: [0, Infinity, false, '> 0', 1],
  octaves: [1, 12, true, 'an integer in [1, 12]', 4],
  lacunarity: [1, 16, false, 'in [1, 16]', 2],
  gain: [0, 1, false, 'in [0, 1]', 0.5],
  offset: [0, Infinity, false, '>= 0', 1],
  scale: [0, Infinity, false, '>= 0', 0.5],
};

// The medium's density as {seed, frequency, ...}, or null for a homogeneous medium (no "density").
// Throws an Error naming the key for anything lightvol would refuse.
export function parseDensity(medium, source = 'medium') {
  if (medium.density === undefined) return null;
  const d = medium.density;
  const where = `${source}: density`;
  if (d === null || typeof d !== 'object' || Array.isArray(d)) throw new Error(`${where}: expected an object`);
  if (d.type === 'vdb') throw new Error(`${where}.type: OpenVDB densities ("vdb") are not supported in the browser; use "noise"`);
  if (d.type !== 'noise') throw new Error(`${where}.type: expected "noise", got ${JSON.stringify(d.type)}`);
  const noise = {};
  for (const key of Object.keys(d))
    if (key !== 'type' && !(key in NOISE_KEYS)) throw new Error(`${where}.${key}: unknown key`);
  for (const [key, [lo, hi, integer, range, fallback]] of Object.entries(NOISE_KEYS)) {
    const x = d[key] ?? fallback;
    if (typeof x !== 'number' || !(x >= lo && x <= hi) || (integer && Math.floor(x) !== x) ||
        (key === 'frequency' && !(x > 0)))
      throw new Error(`${where}.${key}: must be ${range}, got ${JSON.stringify(d[key])}`);
    noise[key] = x;
  }
  return noise;
}

// ---- the light's bounds (light_eye_box, light_bounds_exit, light_reach in C++) ----------------

const OMNI_LOOK = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
const OMNI_UP = [[0, -1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0], [0, -1, 0]];

function eyeBox(light) {
  if (light.type === 'omni') {
    const f = light.far;
    return { lo: [-f, -f, -f], hi: [f, f, f] };
  }
  const inv = light.projection.clone().invert();
  const lo = [1e300, 1e300, 1e300], hi = [-1e300, -1e300, -1e300];
  for (let k = 0; k < 8; ++k) {
    const c = new THREE.Vector3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1).applyMatrix4(inv);
    const a = [c.x, c.y, c.z];
    for (let i = 0; i < 3; ++i) { lo[i] = Math.min(lo[i], a[i]); hi[i] = Math.max(hi[i], a[i]); }
  }
  if (light.perspective) hi[2] = 0;
  return { lo, hi };
}

// ---- the passes -----------------------------------------------------------------------------

// One layer k ≥ 1 of the opacity map: τ at layer k − 1 (om_previous) plus σt × the layer's
// midpoint samples of ρ. Fragment (x, face × size + row) is that face's column (x, row).
const OPACITY_STEP = `
uniform highp sampler2D om_previous;
uniform int om_layer;
uniform int om_substeps;
uniform float om_sigma_t;
layout(location = 0) out vec4 out_tau;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  int face = p.y / om_size;
  ivec2 id = ivec2(p.x, p.y - face * om_size);
  vec2 ndc = (2.0 * vec2(id) + 1.0) / float(om_size) - 1.0;
  vec4 n = om_clip_to_world[face] * vec4(ndc, -1.0, 1.0);
  vec4 f = om_clip_to_world[face] * vec4(ndc, 1.0, 1.0);
  vec3 pn = n.xyz / n.w, pf = f.xyz / f.w;
  vec3 origin = om_point == 1 ? om_light_position : pn;
  vec3 dir = normalize(om_point == 1 ? pn - om_light_position : pf - pn);
  float layer = om_range / float(om_layers - 1);
  float h = layer / float(om_substeps);
  float sum = 0.0;
  for (int j = 0; j < om_substeps; ++j)
    sum += density(origin + ((float(om_layer - 1) + (float(j) + 0.5) / float(om_substeps)) * layer) * dir);
  out_tau = vec4(texelFetch(om_previous, p, 0).r + om_sigma_t * sum * h, 0.0, 0.0, 1.0);
}
`;

// Copies a 2D target into the bound layer of a 3D target.
const COPY = `
uniform highp sampler2D source;
layout(location = 0) out vec4 out_value;
void main() { out_value = texelFetch(source, ivec2(gl_FragCoord.xy), 0); }
`;

// The opacity map in a 3D texture for shaders/density_grid.glsl's look-up: x = column, y = face ×
// size + row, z = layer.
const OPACITY_LOOKUP = `#define LIGHTVOL_OPACITY_LOOKUP
#define LIGHTVOL_DENSITY_INTEGRAND
uniform highp sampler3D om_tau;
#define om_fetch(f_, c_, r_, k_) texelFetch(om_tau, ivec3((c_), (f_) * om_size + (r_), (k_)), 0).x
`;

// The grid: two passes per slice with density_grid.glsl's d_integrand. gl_FragCoord is the
// column's centre in pixels (airlight.glsl's pixel_ray reads it).
const GRID_COMMON = `
uniform int grid_tile;
uniform int grid_slices;
uniform int grid_substeps;
uniform highp sampler2D grid_reach;
uniform highp sampler2D grid_state;   // (D, eye-side optical depth, t) at the previous slice
// The column's ray, its t1 and its angle at the light there (slices uniform in airlight.glsl's
// grid_coordinate; density_grid.glsl's grid_node gives their distances).
float grid_setup(ivec2 id, out float psi1) {
  lv_frag_coord = vec4((vec2(id) + 0.5) * float(grid_tile), 0.0, 1.0);
  pixel_ray(g_ray_origin, g_ray_dir);
  float t1 = texelFetch(grid_reach, id, 0).r;
  psi1 = light_type == 1 ? 0.0 : grid_light_angle(light_position - g_ray_origin, g_ray_dir, t1);
  return t1;
}
`;

const GRID_STEP = `
uniform int grid_slice;
layout(location = 0) out vec4 out_state;
void main() {
  ivec2 id = ivec2(lv_column_coord.xy);
  float psi1;
  float t1 = grid_setup(id, psi1);
  vec3 state = texelFetch(grid_state, id, 0).rgb;
  float d = state.x, tau_e = state.y, t0 = state.z;
  if (!(t1 > 0.0)) { out_state = vec4(0.0, 0.0, 0.0, 1.0); return; }
  float tk = grid_node(float(grid_slice) / float(grid_slices - 1), t0, t1, psi1);
  float dt = (tk - t0) / float(grid_substeps);
  for (int j = 0; j < grid_substeps; ++j) {
    float t = t0 + (float(j) + 0.5) * dt;
    float rho = density(g_ray_origin + t * g_ray_dir);
    d += d_integrand(t, rho, tau_e + 0.5 * sigma_t * rho * dt) * dt;
    tau_e += sigma_t * rho * dt;
  }
  out_state = vec4(d, tau_e, tk, 1.0);
}
`;

// (D, dD/dw) at the slice the state has reached.
const GRID_LAYER = `
layout(location = 0) out vec4 out_d;
void main() {
  ivec2 id = ivec2(lv_column_coord.xy);
  float psi1;
  float t1 = grid_setup(id, psi1);
  vec3 state = texelFetch(grid_state, id, 0).rgb;
  if (!(t1 > 0.0)) { out_d = vec4(0.0, 0.0, 0.0, 1.0); return; }
  float t = state.z;
  out_d = vec4(state.x, d_integrand(t, density(g_ray_origin + t * g_ray_dir), state.y) /
                            grid_coordinate_rate(t, t1, psi1), 0.0, 1.0);
}
`;

// The surfaces' transmittance e^(−τ_E(t_surface)) through the density, per pixel (the composite's
// dimming of the lit scene, as `lightvol render --composite`'s add_constant_surfaces): σt ∫ρ along
// the pixel's ray to its surface by 4-point Gauss–Legendre panels of at most twice the density's
// finest wavelength; 0 where the ray hits nothing (e^(−∞)).
const THROUGH = `
uniform highp sampler2D surface_distance;
uniform float through_step;
layout(location = 0) out vec4 out_through;
void main() {
  lv_frag_coord = gl_FragCoord;
  vec3 origin, dir;
  pixel_ray(origin, dir);
  float t = texelFetch(surface_distance, ivec2(gl_FragCoord.xy), 0).r;
  if (!(t < 1e38)) { out_through = vec4(0.0, 0.0, 0.0, 1.0); return; }
  int panels = clamp(int(ceil(t / through_step)), 1, 65536);
  float width = t / float(panels), sum = 0.0;
  for (int p = 0; p < panels; ++p) {
    float mid = (float(p) + 0.5) * width;
    for (int i = 0; i < 4; ++i) {
      float dx = 0.5 * width * GL_X[i];
      sum += GL_W[i] * (density(origin + (mid - dx) * dir) + density(origin + (mid + dx) * dir));
    }
  }
  out_through = vec4(exp(-sigma_t * sum * 0.5 * width), 0.0, 0.0, 1.0);
}
`;

const FULL_SCREEN_VERTEX = `
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
`;

const PREFIX = 'precision highp float;\nprecision highp int;\nprecision highp sampler2D;\n';

function floatTarget(width, height, format, depth = 0) {
  const options = {
    type: THREE.FloatType, format, depthBuffer: false, stencilBuffer: false,
    minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, generateMipmaps: false,
  };
  return depth > 0 ? new THREE.WebGL3DRenderTarget(width, height, depth, options)
                   : new THREE.WebGLRenderTarget(width, height, options);
}

export const DENSITY_DEFAULTS = { tile: 0, slices: 128, substeps: 2,
                                  opacity: { size: 64, layers: 64, substeps: 4 } };

// The shader files a DensityGrid needs besides airlight.glsl, fetched as they are.
export async function loadDensityShaders(base = new URL('../shaders/', import.meta.url)) {
  const text = async (name) => {
    const url = new URL(name, base).href;
    const response = await fetch(url);
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
    return response.text();
  };
  const [density, grid] = await Promise.all([text('density.glsl'), text('density_grid.glsl')]);
  return { density, grid };
}

// The per-frame density grid for AirlightRenderer (constructed with { density: true }).
// glsl: shaders/airlight.glsl; shaders: loadDensityShaders()'s {density, grid} (density.glsl,
// density_grid.glsl); lightJson: the light's lightvol JSON (the GLB's extras) and light its
// parseFrame(); noise: parseDensity()'s result.
export class DensityGrid {
  constructor(airlight, glsl, shaders, lightJson, light, noise, options = DENSITY_DEFAULTS) {
    this.airlight = airlight;
    this.renderer = airlight.renderer;
    this.gl = airlight.gl;
    this.options = { ...DENSITY_DEFAULTS, ...options,
                     opacity: { ...DENSITY_DEFAULTS.opacity, ...(options.opacity ?? {}) } };
    const { size, layers } = this.options.opacity;
    if (!(size >= 2 && size <= 1024 && layers >= 2 && layers <= 4096))
      throw new Error(`opacity map: size must be in [2, 1024], layers in [2, 4096], got ${size} and ${layers}`);
    if (!(this.options.slices >= 2 && this.options.slices <= 4096))
      throw new Error(`density grid: slices must be in [2, 4096], got ${this.options.slices}`);
    this.light = light;
    const omni = light.type === 'omni';
    this.faces = omni ? 6 : 1;
    // far from the projection (lightvol's GLB extras give view and projection only).
    const p = light.projection.elements, p22 = p[10], p23 = p[14];
    const far = lightJson.far ?? (light.perspective ? p23 / (p22 + 1) : (p23 - 1) / p22);
    this.light = { ...light, far };
    this.worldToClip = [];
    for (let f = 0; f < this.faces; ++f) {
      const view = omni ? new THREE.Matrix4().set(...lookAt([light.position.x, light.position.y, light.position.z],
                                                             OMNI_LOOK[f], OMNI_UP[f]))
                        : light.view;
      this.worldToClip.push(new THREE.Matrix4().multiplyMatrices(light.projection, view));
    }
    // The opacity map's full range: the farthest frustum corner (omni: the cube's), or the depth range.
    if (light.type === 'directional') {
      this.fullRange = far - light.near;
    } else {
      const inv = this.worldToClip[0].clone().invert();
      this.fullRange = 0;
      for (let k = 0; k < 4; ++k) {
        const c = new THREE.Vector3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, 1).applyMatrix4(inv);
        this.fullRange = Math.max(this.fullRange, c.distanceTo(light.position));
      }
    }
    this.box = eyeBox(this.light);

    const u = airlight.common;
    const identity = () => Array.from({ length: 6 }, () => new THREE.Matrix4());
    this.uniforms = {
      density_type: { value: 1 },
      density_seed: { value: noise.seed >>> 0 },
      density_frequency: { value: noise.frequency },
      density_octaves: { value: noise.octaves },
      density_lacunarity: { value: noise.lacunarity },
      density_gain: { value: noise.gain },
      density_offset: { value: noise.offset },
      density_scale: { value: noise.scale },
      om_size: { value: size },
      om_layers: { value: layers },
      om_faces: { value: this.faces },
      om_point: { value: light.perspective ? 1 : 0 },
      om_range: { value: this.fullRange },
      om_light_position: { value: light.position.clone() },
      om_light_direction: { value: light.direction.clone() },
      om_near: { value: light.near },
      om_world_to_clip: { value: identity() },
      om_clip_to_world: { value: identity() },
      om_substeps: { value: this.options.opacity.substeps },
      om_sigma_t: u.sigma_t,
      om_tau: { value: null },
      om_previous: { value: null },
      om_layer: { value: 0 },
      grid_tile: { value: 1 },
      grid_slices: { value: this.options.slices },
      grid_substeps: { value: this.options.substeps },
      grid_columns: { value: new THREE.Vector2(1, 1) },
      grid_reach: { value: null },
      grid_state: { value: null },
      grid_slice: { value: 0 },
      grid_texture: { value: null },
      source: { value: null },
    };
    for (let f = 0; f < this.faces; ++f) {
      this.uniforms.om_world_to_clip.value[f].copy(this.worldToClip[f]);
      this.uniforms.om_clip_to_world.value[f].copy(this.worldToClip[f]).invert();
    }
    const material = (fragment) => new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: PREFIX + FULL_SCREEN_VERTEX,
      fragmentShader: fragment,
      uniforms: { ...u, ...this.uniforms },
      depthTest: false, depthWrite: false,
    });
    // The grid passes use airlight.glsl's common part (pixel_ray, phase, profile) with the
    // column's centre for gl_FragCoord, as gl_density.cpp's compute shader does.
    const common = glsl.replace(/gl_FragCoord/g, 'lv_frag_coord');
    this.opacityStep = material(PREFIX + shaders.density + shaders.grid + OPACITY_STEP);
    this.copy = material(PREFIX + COPY);
    const gridSource = (main) =>
      `${PREFIX}#define LIGHTVOL_COMMON\nvec4 lv_frag_coord;\n#define lv_column_coord gl_FragCoord\n` +
      `${common}\n${shaders.density}${OPACITY_LOOKUP}${shaders.grid}${GRID_COMMON}${main}`;
    this.gridStep = material(gridSource(GRID_STEP));
    this.gridLayer = material(gridSource(GRID_LAYER));
    this.throughPass = material(
      `${PREFIX}#define LIGHTVOL_COMMON\nvec4 lv_frag_coord;\n${common}\n${shaders.density}${THROUGH}`);
    this.throughPass.uniforms.surface_distance = { value: airlight.surfaceTarget.texture };
    this.throughPass.uniforms.through_step = {
      value: 2 / (noise.frequency * noise.lacunarity ** (noise.octaves - 1)) };
    this.throughTarget = floatTarget(airlight.width, airlight.height, THREE.RedFormat);
    const triangle = new THREE.BufferGeometry();
    triangle.setAttribute('position', new THREE.BufferAttribute(new Float32Array(9), 3));
    this.quad = new THREE.Mesh(triangle, this.copy);
    this.quad.frustumCulled = false;
    this.scene = new THREE.Scene();
    this.scene.add(this.quad);
    this.camera = new THREE.Camera();

    const rows = size * this.faces;
    this.opacityState = [floatTarget(size, rows, THREE.RedFormat), floatTarget(size, rows, THREE.RedFormat)];
    this.opacity = floatTarget(size, rows, THREE.RedFormat, layers);
    this.uniforms.om_tau.value = this.opacity.texture;
    this.columns = null;
  }

  draw(material, target, layer = 0) {
    this.quad.material = material;
    this.renderer.setRenderTarget(target, layer);
    this.renderer.render(this.scene, this.camera);
  }

  clear(target) {
    this.renderer.setRenderTarget(target);
    this.gl.clearBufferfv(this.gl.COLOR, 0, new Float32Array([0, 0, 0, 0]));
  }

  // The automatic tile: one column per pixel while the grid stays within 2^25 samples.
  tileFor(width, height) {
    if (this.options.tile > 0) return this.options.tile;
    let tile = 1;
    const samples = (t) => Math.ceil(width / t) * Math.ceil(height / t) * this.options.slices;
    while (samples(tile) > 33554432 && tile < 256) ++tile;
    return tile;
  }

  // Recomputes the opacity map and the grid for a camera {view, projection, flipY, width,
  // height} and the scene's distances along its pixel rays (AirlightRenderer.readSurface(): top
  // row first, ≥ 1e38 where nothing is hit). Then binds the grid to the airlight's materials.
  update(camera, surface) {
    const { renderer } = this;
    const { width: w, height: h } = camera;
    const light = this.light;
    // What each pixel needs: its surface, or where its ray leaves the light's bounds if nearer;
    // and the farthest from the light any of them gets (the opacity map's reach).
    const inv = new THREE.Matrix4().multiplyMatrices(camera.projection, camera.view).invert();
    const lightView = light.view.elements;  // column-major
    const toLight = (v, w1) => [
      lightView[0] * v[0] + lightView[4] * v[1] + lightView[8] * v[2] + w1 * lightView[12],
      lightView[1] * v[0] + lightView[5] * v[1] + lightView[9] * v[2] + w1 * lightView[13],
      lightView[2] * v[0] + lightView[6] * v[1] + lightView[10] * v[2] + w1 * lightView[14]];
    const lp = [light.position.x, light.position.y, light.position.z];
    const ld = [light.direction.x, light.direction.y, light.direction.z];
    const perspectiveCamera = camera.projection.elements[11] !== 0;
    const eye = new THREE.Vector3(0, 0, 0).applyMatrix4(camera.view.clone().invert());
    const lightDistance = (x) => (light.perspective
      ? Math.hypot(x[0] - lp[0], x[1] - lp[1], x[2] - lp[2])
      : (x[0] - lp[0]) * ld[0] + (x[1] - lp[1]) * ld[1] + (x[2] - lp[2]) * ld[2] - light.near);
    const need = new Float64Array(w * h);
    // A point light's columns are read by angle (airlight.glsl's grid_column_at_angle): the sine
    // and cosine of each pixel's angle ψ at the light from its ray's origin to its needed point.
    const sinPsi = new Float64Array(w * h), cosPsi = new Float64Array(w * h).fill(1);
    const lightH = (a, d) => Math.max(Math.hypot(d[1] * a[2] - d[2] * a[1], d[2] * a[0] - d[0] * a[2],
                                                 d[0] * a[1] - d[1] * a[0]),
                                      1e-6 * Math.max(1, Math.hypot(...a)));
    const dot3 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let reach = 0;
    const near = new THREE.Vector3(), far = new THREE.Vector3();
    for (let row = 0; row < h; ++row)
      for (let col = 0; col < w; ++col) {
        const x = 2 * (col + 0.5) / w - 1;
        const yy = 1 - 2 * (row + 0.5) / h;
        const y = camera.flipY ? -yy : yy;
        near.set(x, y, -1).applyMatrix4(inv);
        far.set(x, y, 1).applyMatrix4(inv);
        const dir = far.clone().sub(near).normalize();
        const origin = perspectiveCamera ? eye : near;
        const o = [origin.x, origin.y, origin.z], d = [dir.x, dir.y, dir.z];
        // light_bounds_exit
        let lo, dd;
        if (light.type === 'omni') {
          lo = [o[0] - lp[0], o[1] - lp[1], o[2] - lp[2]];
          dd = d;
        } else {
          lo = toLight(o, 1);
          dd = toLight(d, 0);
        }
        let t0 = 0, t1 = Infinity, hit = true;
        for (let a = 0; a < 3 && hit; ++a) {
          if (dd[a] === 0) {
            if (lo[a] < this.box.lo[a] || lo[a] > this.box.hi[a]) hit = false;
            continue;
          }
          let ta = (this.box.lo[a] - lo[a]) / dd[a], tb = (this.box.hi[a] - lo[a]) / dd[a];
          if (ta > tb) [ta, tb] = [tb, ta];
          t0 = Math.max(t0, ta);
          t1 = Math.min(t1, tb);
        }
        const exit = hit && t1 > t0 ? t1 : 0;
        const s = surface[row * w + col];
        const n = Math.min(s >= 1e38 ? Infinity : s, exit);
        need[row * w + col] = n;
        if (!(n > 0)) continue;
        if (light.perspective) {
          const a = [lp[0] - o[0], lp[1] - o[1], lp[2] - o[2]];
          const psi = Math.atan2(n * lightH(a, d), dot3(a, a) - n * dot3(a, d));
          sinPsi[row * w + col] = Math.sin(psi);
          cosPsi[row * w + col] = Math.cos(psi);
        }
        reach = Math.max(reach, lightDistance(o),
                         lightDistance([o[0] + n * d[0], o[1] + n * d[1], o[2] + n * d[2]]));
      }
    reach *= 1.001;
    const tile = this.tileFor(w, h);
    const cx = Math.ceil(w / tile), cy = Math.ceil(h / tile);
    const t1 = new Float32Array(cx * cy);
    // Each column's ray (GL coordinates: row 0 at the bottom) when read by angle.
    const byAngle = light.perspective && tile > 1;
    const columnRays = [];
    if (byAngle)
      for (let y = 0; y < cy; ++y)
        for (let x = 0; x < cx; ++x) {
          const nx = 2 * (x + 0.5) * tile / w - 1;
          const ny = (camera.flipY ? -1 : 1) * (2 * (y + 0.5) * tile / h - 1);
          near.set(nx, ny, -1).applyMatrix4(inv);
          far.set(nx, ny, 1).applyMatrix4(inv);
          const dir = far.clone().sub(near).normalize();
          const origin = perspectiveCamera ? eye : near;
          columnRays.push({ a: [lp[0] - origin.x, lp[1] - origin.y, lp[2] - origin.z],
                            d: [dir.x, dir.y, dir.z] });
        }
    // Each column reaches the farthest point any pixel interpolated from it needs (by angle: the
    // column's point at the pixel's ψ, at most twice the pixel's distance), as gl_density.cpp.
    for (let row = 0; row < h; ++row) {
      const glRow = camera.flipY ? row : h - 1 - row;
      for (let col = 0; col < w; ++col) {
        const n = need[row * w + col];
        if (!(n > 0)) continue;
        const qx = (col + 0.5) / tile - 0.5, qy = (glRow + 0.5) / tile - 0.5;
        const x0 = Math.min(Math.max(Math.floor(qx), 0), cx - 1);
        const y0 = Math.min(Math.max(Math.floor(qy), 0), cy - 1);
        const sp = sinPsi[row * w + col], cp = cosPsi[row * w + col];
        for (let dy = 0; dy < 2; ++dy)
          for (let dx = 0; dx < 2; ++dx) {
            const i = Math.min(y0 + dy, cy - 1) * cx + Math.min(x0 + dx, cx - 1);
            let r = n;
            if (byAngle) {
              const { a, d } = columnRays[i];
              const den = lightH(a, d) * cp + dot3(a, d) * sp;
              r = den > 0 ? Math.min(2 * n, dot3(a, a) * sp / den) : 2 * n;
            }
            t1[i] = Math.max(t1[i], Math.fround(r * (1 + 1e-6)));
          }
      }
    }
    const u = this.uniforms;
    u.om_range.value = reach > 0 ? Math.min(this.fullRange, reach) : this.fullRange;
    u.grid_tile.value = tile;
    u.grid_columns.value.set(cx, cy);
    if (!this.columns || this.columns.width !== cx || this.columns.height !== cy) {
      for (const t of [this.columns, this.gridState?.[0], this.gridState?.[1], this.grid]) t?.dispose();
      this.columns = { width: cx, height: cy };
      this.gridState = [floatTarget(cx, cy, THREE.RGBAFormat), floatTarget(cx, cy, THREE.RGBAFormat)];
      this.grid = floatTarget(cx, cy, THREE.RGFormat, this.options.slices);
      this.reachTexture?.dispose();
      this.reachTexture = new THREE.DataTexture(t1, cx, cy, THREE.RedFormat, THREE.FloatType);
      this.reachTexture.minFilter = this.reachTexture.magFilter = THREE.NearestFilter;
    }
    this.reachTexture.image.data.set(t1);
    this.reachTexture.needsUpdate = true;
    u.grid_reach.value = this.reachTexture;
    u.grid_texture.value = this.grid.texture;

    const previousTarget = renderer.getRenderTarget();
    const autoClear = renderer.autoClear;
    renderer.autoClear = false;
    // The opacity map, layer by layer.
    let [a, b] = this.opacityState;
    this.clear(a);
    u.source.value = a.texture;
    this.draw(this.copy, this.opacity, 0);
    for (let k = 1; k < this.options.opacity.layers; ++k) {
      u.om_previous.value = a.texture;
      u.om_layer.value = k;
      this.draw(this.opacityStep, b);
      u.source.value = b.texture;
      this.draw(this.copy, this.opacity, k);
      [a, b] = [b, a];
    }
    // The grid, slice by slice.
    [a, b] = this.gridState;
    this.clear(a);
    u.grid_state.value = a.texture;
    this.draw(this.gridLayer, this.grid, 0);
    for (let k = 1; k < this.options.slices; ++k) {
      u.grid_state.value = a.texture;
      u.grid_slice.value = k;
      this.draw(this.gridStep, b);
      u.grid_state.value = b.texture;
      this.draw(this.gridLayer, this.grid, k);
      [a, b] = [b, a];
    }
    // The surfaces' transmittance, for the composite.
    if (this.throughTarget.width !== w || this.throughTarget.height !== h) this.throughTarget.setSize(w, h);
    this.draw(this.throughPass, this.throughTarget);
    renderer.setRenderTarget(previousTarget);
    renderer.autoClear = autoClear;
    this.airlight.setDensityGrid(this);
  }
}

export { stageSource };
