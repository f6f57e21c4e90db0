// LightVolume: exact volumetric light shafts for a three.js SpotLight, DirectionalLight or
// PointLight with castShadow (docs/web.md). Every frame it copies the shadow map three.js has just
// rendered for that light (its own depth texture: window depth, one 2D map, or the six faces of a
// point light's cube map), builds `lightvol build`'s static light volume of that map on the GPU
// (shaders/airlight.glsl, stage LIGHTVOL_LIVE_VOLUME_VERTEX: vertex gl_VertexID from texelFetch of
// the map, build's triangles as the index buffer, made here once per map size) and renders the
// single-scattering airlight with the same file's passes (web/airlight.js) into a float target the
// app composites.
//
//   const glsl = await LightVolume.loadShader();               // shaders/airlight.glsl
//   const volume = new LightVolume(renderer, light, { glsl, width, height, medium });
//   // each frame, after renderer.render(scene, camera) (which renders the light's shadow map):
//   volume.render(scene, camera);   // volume.airlightTexture: the airlight (R32F), linear
//
// Errors (a light without castShadow, shadows off, a shadow map it cannot read, a browser without
// float render targets or float blending) are thrown as Error with a message that says what to do.
import * as THREE from 'three';
import { AirlightRenderer, lookAt, parseFrame, stageSource, toMatrix4 } from './airlight.js';
import { AdaptiveVolume } from './live_adaptive.js';

// ---- lightvol's texel rays (src/lightvol/light/light.cpp, Unprojector), in double -------------

const OMNI_LOOK = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
const OMNI_UP = [[0, -1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0], [0, -1, 0]];
const OMNI_FACES = 6;

// The texels of one W×H map of a light with `view` (world → eye) and `projection` (THREE.Matrix4),
// first stored row the top of the view unless flipY; points in world space.
class Texels {
  constructor(view, projection, width, height, flipY, directional) {
    this.width = width;
    this.height = height;
    this.flipY = flipY;
    this.invProjection = projection.clone().invert();
    this.toWorld = view.clone().invert();
    const a = this.eyeNear(0, 0), b = this.eyeNear(1, 0), c = this.eyeNear(0, 1);
    const facing = -new THREE.Vector3().crossVectors(b.clone().sub(a), c.clone().sub(a)).z;
    const det3 = new THREE.Matrix3().setFromMatrix4(this.toWorld).determinant();
    this.standard = (facing > 0) === (det3 > 0);
    this.minT = 0;
    if (directional) {
      let maxAbs = 0;
      for (const col of [0, width - 1])
        for (const row of [0, height - 1])
          for (const p of [this.nearPoint(col, row), this.farPoint(col, row)])
            maxAbs = Math.max(maxAbs, Math.abs(p.x), Math.abs(p.y), Math.abs(p.z));
      const rayLength = this.farPoint(0, 0).distanceTo(this.nearPoint(0, 0));
      this.minT = Math.min(0.5, maxAbs * 2 ** (-23 + 6) / rayLength);
    }
  }
  ndc(col, row) {
    const down = 2 * (row + 0.5) / this.height - 1;
    return [2 * (col + 0.5) / this.width - 1, this.flipY ? down : -down];
  }
  eyeNear(col, row) {
    const [x, y] = this.ndc(col, row);
    return new THREE.Vector3(x, y, -1).applyMatrix4(this.invProjection);
  }
  nearPoint(col, row) { return this.eyeNear(col, row).applyMatrix4(this.toWorld); }
  farPoint(col, row) {
    const [x, y] = this.ndc(col, row);
    return new THREE.Vector3(x, y, 1).applyMatrix4(this.invProjection).applyMatrix4(this.toWorld);
  }
  apex() { return new THREE.Vector3(0, 0, 0).applyMatrix4(this.toWorld); }
}

// ---- build's triangles (src/lightvol/volume/static_volume.cpp, closing.cpp, omni_volume.cpp) ----

// Grid triangles of a W-wide grid's quad rows, two per texel quad, wound to face away from the
// light, into `out` from `at`; vertex `first` + row·W + col.
function gridTriangles(out, at, width, height, standard, first = 0) {
  for (let r = 0; r + 1 < height; ++r)
    for (let c = 0; c + 1 < width; ++c) {
      const a = first + r * width + c, b = a + 1, cc = a + width, d = cc + 1;
      if (standard) out.set([a, b, cc, b, d, cc], at);
      else out.set([a, cc, b, b, cc, d], at);
      at += 6;
    }
  return at;
}

// The border ring of a W×H grid (border_loop): top row left to right, right column down, bottom row
// right to left, left column up; reversed unless standard.
function borderLoop(width, height, standard) {
  const loop = [];
  for (let c = 0; c < width - 1; ++c) loop.push(c);
  for (let r = 0; r < height - 1; ++r) loop.push(r * width + width - 1);
  for (let c = width - 1; c > 0; --c) loop.push((height - 1) * width + c);
  for (let r = height - 1; r > 0; --r) loop.push(r * width);
  if (!standard) loop.reverse();
  return loop;
}

// static_volume_counts.
export function staticVolumeCounts(type, width, height) {
  const grid = 2 * (width - 1) * (height - 1), border = 2 * (width - 1) + 2 * (height - 1);
  if (type === 'spot') return { vertices: width * height + 1, triangles: grid + border };
  if (type === 'directional') return { vertices: width * height + border + 1, triangles: grid + 3 * border };
  return { vertices: 6 * width * width, triangles: 6 * grid + 24 * (width - 1) + 8 };
}

// static_volume_indices: the grid, then the spot's fan (next, cur, apex) or the directional walls
// and cap, per ring edge.
export function staticVolumeIndices(type, width, height, standard) {
  const counts = staticVolumeCounts(type, width, height);
  const out = new Uint32Array(3 * counts.triangles);
  let at = gridTriangles(out, 0, width, height, standard);
  const ring = borderLoop(width, height, standard), n = ring.length, grid = width * height;
  for (let k = 0; k < n; ++k) {
    const cur = ring[k], next = ring[(k + 1) % n];
    if (type === 'spot') {
      out.set([next, cur, grid], at);
      at += 3;
    } else {
      const curN = grid + k, nextN = grid + (k + 1) % n, cap = grid + n;
      out.set([next, cur, curN, next, curN, nextN, nextN, curN, cap], at);
      at += 9;
    }
  }
  if (at !== out.length) throw new Error('LightVolume: internal error: static volume index count');
  return out;
}

const BORDERS = ['top', 'bottom', 'left', 'right'];
function borderTexel(border, width, k) {
  if (border === 'top') return [k, 0];
  if (border === 'bottom') return [k, width - 1];
  if (border === 'left') return [0, k];
  return [width - 1, k];
}
function dominantAxis(v, excluded) {
  let best = -1;
  for (let a = 0; a < 3; ++a)
    if (a !== excluded && (best < 0 || Math.abs(v[a]) > Math.abs(v[best]))) best = a;
  return { axis: best, sign: v[best] > 0 ? 1 : -1 };
}
const det3 = (a, b, c) => a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                          a[2] * (b[0] * c[1] - b[1] * c[0]);

// omni_adjacency: which border of which face meets which across the twelve cube edges, and the
// eight corners, derived from 2×2 faces' texel rays as lightvol derives them.
function omniAdjacency(faceTexels) {
  const last = 1;
  const dir = (f, col, row) => faceTexels[f].nearPoint(col, row).sub(faceTexels[f].apex()).toArray();
  const dirOn = (f, border, k) => dir(f, ...borderTexel(border, 2, k));
  const axes = [];
  for (let f = 0; f < OMNI_FACES; ++f) {
    const c = [0, 1, 2].map((i) => dir(f, 0, 0)[i] + dir(f, last, 0)[i] + dir(f, 0, last)[i] + dir(f, last, last)[i]);
    axes.push(dominantAxis(c, -1));
  }
  const cubePoint = (f, border, k) => {
    const d = dirOn(f, border, k), s = 1 / Math.abs(d[axes[f].axis]);
    return d.map((x) => s * x);
  };
  const faceOn = [[-1, -1], [-1, -1], [-1, -1]];
  for (let f = 0; f < OMNI_FACES; ++f) faceOn[axes[f].axis][axes[f].sign > 0 ? 1 : 0] = f;
  const across = [];
  for (let f = 0; f < OMNI_FACES; ++f) {
    across.push(BORDERS.map((b) => {
      const p0 = cubePoint(f, b, 0), p1 = cubePoint(f, b, last);
      const { axis, sign } = dominantAxis([0, 1, 2].map((i) => 0.5 * (p0[i] + p1[i])), axes[f].axis);
      return faceOn[axis][sign > 0 ? 1 : 0];
    }));
  }
  const seams = [];
  for (let f = 0; f < OMNI_FACES; ++f)
    for (let b = 0; b < 4; ++b) {
      const g = across[f][b];
      if (g < f) continue;
      const bg = across[g].indexOf(f);
      const border = [BORDERS[b], BORDERS[bg]];
      const edgeAxis = 3 - axes[f].axis - axes[g].axis;
      const stepA = cubePoint(f, border[0], last)[edgeAxis] - cubePoint(f, border[0], 0)[edgeAxis];
      const stepB = cubePoint(g, border[1], last)[edgeAxis] - cubePoint(g, border[1], 0)[edgeAxis];
      const reversed = (stepA > 0) !== (stepB > 0);
      const a0 = dirOn(f, border[0], 0), a1 = dirOn(f, border[0], 1);
      const b0 = dirOn(g, border[1], reversed ? last : 0);
      seams.push({ face: [f, g], border, reversed, flip: det3(a0, a1, b0) < 0 });
    }
  const corners = Array.from({ length: 8 }, () => ({ face: [], lastCol: [], lastRow: [] }));
  for (let f = 0; f < OMNI_FACES; ++f)
    for (let lr = 0; lr < 2; ++lr)
      for (let lc = 0; lc < 2; ++lc) {
        const d = dir(f, lc * last, lr * last);
        const corner = corners[(d[0] > 0 ? 1 : 0) | (d[1] > 0 ? 2 : 0) | (d[2] > 0 ? 4 : 0)];
        corner.face.push(f);
        corner.lastCol.push(lc === 1);
        corner.lastRow.push(lr === 1);
      }
  for (const corner of corners) {
    const d = [0, 1, 2].map((k) => dir(corner.face[k], corner.lastCol[k] ? last : 0, corner.lastRow[k] ? last : 0));
    if (det3(d[0], d[1], d[2]) < 0)
      for (const key of ['face', 'lastCol', 'lastRow']) [corner[key][1], corner[key][2]] = [corner[key][2], corner[key][1]];
  }
  if (seams.length !== 12 || corners.some((c) => c.face.length !== 3))
    throw new Error('LightVolume: internal error: the omni faces do not make a cube');
  return { seams, corners };
}

// omni_volume_indices: six face grids (face f's texel (col, row) is vertex f·W² + row·W + col),
// the twelve seams, the eight corners.
export function omniVolumeIndices(width, faceStandard, adjacency) {
  const out = new Uint32Array(3 * staticVolumeCounts('omni', width, width).triangles);
  const w2 = width * width;
  let at = 0;
  for (let f = 0; f < OMNI_FACES; ++f) at = gridTriangles(out, at, width, width, faceStandard[f], f * w2);
  const vertex = (f, [col, row]) => f * w2 + row * width + col;
  const emit = (a, b, c, flip) => { out.set(flip ? [a, c, b] : [a, b, c], at); at += 3; };
  for (const seam of adjacency.seams) {
    const v = (side, k) => vertex(seam.face[side],
                                  borderTexel(seam.border[side], width, side === 1 && seam.reversed ? width - 1 - k : k));
    for (let k = 0; k + 1 < width; ++k) {
      emit(v(0, k), v(0, k + 1), v(1, k), seam.flip);
      emit(v(0, k + 1), v(1, k + 1), v(1, k), seam.flip);
    }
  }
  for (const c of adjacency.corners)
    emit(...[0, 1, 2].map((k) => vertex(c.face[k], [c.lastCol[k] ? width - 1 : 0, c.lastRow[k] ? width - 1 : 0])), false);
  if (at !== out.length) throw new Error('LightVolume: internal error: omni volume index count');
  return out;
}

// ---- the draw's vertex numbering ---------------------------------------------------------------

// The grid's vertex ids a row in the draw (LIGHTVOL_LIVE_PITCH): W, unless W is 0 or 1 modulo 64,
// then W + 32. SwiftShader (the software WebGL of headless chromium) keeps transformed vertices in
// a 64-entry cache indexed by id modulo 64: with rows W ≡ 0 apart, a texel and the one below it
// take the same entry and each quad runs the vertex shader about 3 times for 4 lanes; with
// another pitch, about once (docs/web.md). build's triangles, renumbered.
export function livePitch(width) {
  return width % 64 <= 1 ? width + 32 : width;
}

// build's vertex v (grid row·W + col, omni face·W·H + row·W + col, then the closing's) as the draw
// numbers it, and back.
export function drawVertexId(v, width, height, pitch, faces) {
  const texels = width * height;
  if (v >= faces * texels) return v - faces * texels + faces * pitch * height;
  const f = Math.floor(v / texels), i = v - f * texels;
  return f * pitch * height + Math.floor(i / width) * pitch + i % width;
}
export function buildVertexId(id, width, height, pitch, faces) {
  const ids = pitch * height;
  if (id >= faces * ids) return id - faces * ids + faces * width * height;
  const f = Math.floor(id / ids), i = id - f * ids, col = i % pitch;
  if (col >= width) throw new Error(`LightVolume: internal error: vertex id ${id} is in no grid column`);
  return f * width * height + Math.floor(i / pitch) * width + col;
}

// build's triangles in the order the draw sends them: each grid row's quads in groups of three,
// first the three quads' second triangles, each turned so that its new vertex (the quad's lower
// right) comes first (the group's first quad: its lower left first), then their first triangles;
// the closing, seams and corners after, as build orders them. A miss in SwiftShader's vertex
// cache runs the shader on the next 4 indices: this way they hold 2–3 vertices not yet made (a
// simulation of that cache: 0.70 runs a quad against 1.0 in build's order). Returns the indices
// and, for each drawn triangle, build's triangle and how far its corners were turned.
export function cacheOrder(indices, width, height, faces) {
  const triangles = indices.length / 3, grid = 2 * (width - 1) * (height - 1);
  const order = new Uint32Array(triangles), turn = new Uint8Array(triangles), out = new Uint32Array(indices.length);
  let at = 0;
  const put = (t, first) => {
    const k = [0, 1, 2].find((j) => indices[3 * t + j] === first);
    if (k === undefined) throw new Error('LightVolume: internal error: a grid triangle without its corner');
    for (let j = 0; j < 3; ++j) out[3 * at + j] = indices[3 * t + (k + j) % 3];
    order[at] = t;
    turn[at++] = k;
  };
  for (let f = 0; f < faces; ++f)
    for (let r = 0; r + 1 < height; ++r)
      for (let c0 = 0; c0 + 1 < width; c0 += 3) {
        const quads = [];
        for (let c = c0; c < Math.min(c0 + 3, width - 1); ++c) quads.push(f * grid + 2 * (r * (width - 1) + c));
        const below = (c) => f * width * height + (r + 1) * width + c;
        quads.forEach((t, j) => put(t + 1, j === 0 ? below(c0) : below(c0 + j + 1)));
        quads.forEach((t, j) => put(t, indices[3 * t]));
      }
  for (let t = faces * grid; t < triangles; ++t) put(t, indices[3 * t]);
  if (at !== triangles || new Set(order).size !== triangles)
    throw new Error('LightVolume: internal error: the draw order is not a permutation of build\'s triangles');
  return { indices: out, order, turn };
}

// ---- the light as lightvol describes it ------------------------------------------------------

const rows = (m) => { const e = m.elements; return [0, 1, 2, 3].map((r) => [e[r], e[4 + r], e[8 + r], e[12 + r]]); };

// lightvol's light JSON (docs/formats.md) of a three.js light's shadow camera as it rendered the
// last shadow map: spot and directional lights by their view and projection matrices, point
// lights as omni lights (three.js renders the cube faces with lightvol's face frames). The depth
// encoding is window depth: three.js's shadow maps are depth textures.
export function lightJson(light) {
  const camera = light.shadow.camera;
  if (light.isPointLight) {
    const p = new THREE.Vector3().setFromMatrixPosition(light.matrixWorld);
    return { type: 'omni', position: p.toArray(), near: camera.near, far: camera.far, depth: 'window' };
  }
  return { type: light.isSpotLight ? 'spot' : 'directional', view: rows(camera.matrixWorldInverse),
           projection: rows(camera.projectionMatrix), depth: 'window', flip_y: false };
}

// ---- the addon -------------------------------------------------------------------------------

const SHADER_URL = new URL('../shaders/airlight.glsl', import.meta.url).href;

// A WebGL2 context's lack of what the airlight needs, or null.
export function missingFloatSupport(gl) {
  if (typeof WebGL2RenderingContext === 'undefined' || !(gl instanceof WebGL2RenderingContext))
    return 'LightVolume needs WebGL2 (gl_VertexID and texelFetch); this context is WebGL1';
  for (const name of ['EXT_color_buffer_float', 'EXT_float_blend'])
    if (!gl.getExtension(name))
      return `LightVolume needs float render targets with additive blending (EXT_color_buffer_float ` +
             `and EXT_float_blend); this browser's WebGL2 lacks ${name}, so the airlight cannot be summed`;
  return null;
}

// A medium of varying density needs its per-frame grid (web/density.js), which the live volume does
// not make yet (as lightvol's LiveVolume): refused, never drawn as if homogeneous.
function refuseDensity(medium) {
  if (medium && medium.density !== undefined)
    throw new Error('LightVolume: the medium has a "density": live volumes render homogeneous media only ' +
                    '(the viewer, index.html, renders noise densities)');
}

export class LightVolume {
  // The text of shaders/airlight.glsl (fetched beside this module: ../shaders/airlight.glsl).
  // The text of shaders/live_adaptive_webgl.glsl, for the option maxError.
  static loadAdaptiveShader(url) { return AdaptiveVolume.loadShader(url); }

  static async loadShader(url = SHADER_URL) {
    const response = await fetch(url);
    if (!response.ok) throw new Error(`LightVolume: ${url}: HTTP ${response.status}`);
    return response.text();
  }

  // renderer: a THREE.WebGLRenderer (WebGL2) with shadowMap.enabled; light: a SpotLight,
  // DirectionalLight or PointLight with castShadow; options: glsl (loadShader()'s text), width and
  // height (the airlight target: the camera's image in pixels), medium (lightvol's medium JSON:
  // scattering, absorption, intensity, phase, profile; intensity defaults to the light's), cone
  // (spot lights: shafts only in the SpotLight's cone, as three.js lights it; default true),
  // maxError (build's adaptive volume at that bound, `--adaptive --max-error E --tessellation
  // quadtree`, made on the GPU each frame: live_adaptive.js; point lights: six faces with build's
  // seam rounds and omni closing; with
  // adaptiveGlsl, loadAdaptiveShader()'s text), rounds (its fix-up rounds a frame, default 4) and
  // count ('readback', the default, or 'bound': how its grid draw is sized, live_adaptive.js),
  // resolution (a scale in (0, 1], default 1: the volume's airlight computed on an image that
  // much smaller on each side and taken up to width × height by a depth-aware upsampling,
  // airlight.js; docs/web.md).
  constructor(renderer, light, { glsl, width, height, medium = {}, cone = true, maxError, adaptiveGlsl, rounds, count,
                                 resolution = 1 }) {
    const name = light && (light.name ? `'${light.name}'` : light.type);
    if (!light || !(light.isSpotLight || light.isDirectionalLight || light.isPointLight))
      throw new Error(`LightVolume: ${name ?? 'no light'} is not a SpotLight, DirectionalLight or PointLight`);
    if (!light.castShadow)
      throw new Error(`LightVolume: the light ${name} has castShadow = false: it has no shadow map to ` +
                      `build a light volume from (set light.castShadow = true)`);
    if (!renderer.shadowMap.enabled)
      throw new Error('LightVolume: renderer.shadowMap.enabled is false: three.js renders no shadow maps');
    if (renderer.shadowMap.type === THREE.VSMShadowMap && light.isPointLight)
      throw new Error('LightVolume: three.js makes no point-light shadow maps with VSMShadowMap');
    if (!glsl) throw new Error('LightVolume: options.glsl is empty (LightVolume.loadShader() gives it)');
    refuseDensity(medium);
    const gl = renderer.getContext();
    const missing = missingFloatSupport(gl);
    if (missing) throw new Error(missing);
    this.renderer = renderer;
    this.glsl = glsl;
    this.light = light;
    this.gl = gl;
    this.type = light.isSpotLight ? 'spot' : light.isDirectionalLight ? 'directional' : 'omni';
    if (!(resolution > 0 && resolution <= 1))
      throw new Error(`LightVolume: resolution ${resolution}: a scale in (0, 1] of the camera's image`);
    this.airlight = new AirlightRenderer(renderer, glsl, { width, height, resolution });
    this.medium = medium;
    this.cone = cone;
    this.size = null;        // [W, H] of the current index buffer
    this.copies = [];        // the shadow map's depth, copied: 1 or 6 render targets
    this.live = {
      live_size: { value: new THREE.Vector2(2, 2) },
      live_pitch: { value: 2 },
      live_flip_y: { value: 0 },
      live_depth: { value: 0 },
      live_type: { value: 0 },
      live_standard: { value: 1 },
      live_min_t: { value: 0 },
      live_ray_x: { value: new THREE.Vector4() },
      live_ray_y: { value: new THREE.Vector4() },
      live_near_0: { value: new THREE.Vector4() },
      live_far_0: { value: new THREE.Vector4() },
      live_eye_to_world: { value: Array.from({ length: OMNI_FACES }, () => new THREE.Matrix4()) },
      live_apex: { value: new THREE.Vector3() },
      live_cap: { value: new THREE.Vector3() },
      shadow_maps: { value: [] },
    };
    // LIGHTVOL_SURFACE_FRAGMENT for the app's scene as it is now: world positions from each mesh's
    // own matrixWorld (three.js sets modelMatrix for every program).
    const a = this.airlight;
    this.surfaceMaterial = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: 'precision highp float;\nin vec3 position;\nuniform mat4 modelMatrix;\n' +
                    'uniform mat4 view_projection;\nout vec3 world;\nvoid main() {\n' +
                    '  vec4 w = modelMatrix * vec4(position, 1.0);\n  world = w.xyz;\n' +
                    '  gl_Position = view_projection * w;\n}\n',
      fragmentShader: stageSource(glsl, 'LIGHTVOL_SURFACE_FRAGMENT'),
      uniforms: { ...a.common, view_projection: a.surfaceMaterial.uniforms.view_projection },
      side: THREE.DoubleSide,
    });
    const vu = a.volumeMaterial.uniforms;
    this.volumeMaterial = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: stageSource(`${this.liveDefines()}${glsl}`, 'LIGHTVOL_LIVE_VOLUME_VERTEX'),
      fragmentShader: stageSource(glsl, 'LIGHTVOL_VOLUME_FRAGMENT'),
      uniforms: { ...a.common, surface: vu.surface, baseline: vu.baseline, panels: vu.panels,
                  facing_sign: vu.facing_sign, ...this.live },
      ...a.volumeState,
    });
    this.geometry = new THREE.BufferGeometry();
    this.adaptive = null;
    if (maxError !== undefined) {
      this.adaptive = new AdaptiveVolume(renderer, glsl, adaptiveGlsl, {
        maxError, rounds, count, live: this.live, volumeState: a.volumeState, faces: this.type === 'omni' ? OMNI_FACES : 1,
        volumeUniforms: { ...a.common, surface: vu.surface, baseline: vu.baseline, panels: vu.panels,
                          facing_sign: vu.facing_sign },
        fragmentShader: stageSource(glsl, 'LIGHTVOL_VOLUME_FRAGMENT') });
      for (const m of this.adaptive.meshes) a.volumeScene.add(m);
    } else {
      const mesh = new THREE.Mesh(this.geometry, this.volumeMaterial);
      mesh.frustumCulled = false;
      a.volumeScene.add(mesh);
    }
    // Reads a copied depth map as floats (R32F), for readShadowMap().
    this.readMaterial = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: 'void main() {\n  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);\n' +
                    '  gl_Position = vec4(p, 0.0, 1.0);\n}\n',
      fragmentShader: 'precision highp float;\nprecision highp sampler2D;\nuniform sampler2D map;\n' +
                      'layout(location = 0) out float depth;\n' +
                      'void main() { depth = texelFetch(map, ivec2(gl_FragCoord.xy), 0).r; }\n',
      uniforms: { map: { value: null } },
      depthTest: false, depthWrite: false,
    });
    const triangle = new THREE.BufferGeometry();
    triangle.setAttribute('position', new THREE.BufferAttribute(new Float32Array(9), 3));
    this.readScene = new THREE.Scene();
    const readMesh = new THREE.Mesh(triangle, this.readMaterial);
    readMesh.frustumCulled = false;
    this.readScene.add(readMesh);
    this.lastLight = null;
  }

  // The live stage's defines (shaders/airlight.glsl): ids a row by live_pitch; the light type, the
  // depth encoding (window) and flip (none) as constants; one map for spot and directional lights.
  liveDefines() {
    const type = { spot: 0, directional: 1, omni: 2 }[this.type];
    return `#define LIGHTVOL_LIVE_PITCH\n#define LIGHTVOL_LIVE_TYPE ${type}\n` +
           `${this.type === 'omni' ? '' : '#define LIGHTVOL_LIVE_ONE_MAP\n'}`;
  }

  get airlightTexture() { return this.airlight.airlightTarget.texture; }
  // Distances along the camera's pixel rays to the scene (3e38 where none), R32F.
  get surfaceTexture() { return this.airlight.surfaceTarget.texture; }
  // The static volume's triangles (adaptive volumes: readTriangles().length, read back).
  get triangles() { return this.geometry.index ? this.geometry.index.count / 3 : 0; }

  setMedium(medium) {
    refuseDensity(medium);
    this.medium = medium;
  }
  // The camera's new image size in pixels (renderer.getDrawingBufferSize()); the textures stay the
  // same objects.
  setSize(width, height) { this.airlight.setSize(width, height); }

  // lightvol's medium JSON as the airlight uses it now: the given medium, its intensity the light's
  // unless given, and for a spot light with `cone` (and no profile of its own) the SpotLight's cone
  // as lightvol's soft-edged profile: three.js attenuates a spot by smoothstep(cos angle,
  // cos(angle·(1 − penumbra)), cos α), lightvol's profile by smoothstep(cos outer_deg,
  // cos inner_deg, cos α): the same function (a penumbra under 0.001 is taken as 0.001: lightvol
  // needs inner_deg < outer_deg).
  mediumJson() {
    const { light } = this;
    const medium = { ...this.medium, intensity: this.medium.intensity ?? light.intensity };
    if (light.isSpotLight && this.cone && !medium.profile) {
      const outer = THREE.MathUtils.radToDeg(light.angle);
      medium.profile = { inner_deg: outer * (1 - Math.max(light.penumbra, 1e-3)), outer_deg: outer };
    }
    return medium;
  }

  // Renders the airlight of `light` seen by `camera` through the surfaces of `scene` (its visible
  // meshes, drawn with their current matrices), from the shadow map three.js rendered for the
  // light in the last renderer.render(): call it after that, every frame.
  render(scene, camera) {
    const { renderer, light, airlight } = this;
    this.copyShadowMap();
    const json = lightJson(light);
    this.lastLight = json;
    this.setUniforms(json);
    if (this.adaptive) this.adaptive.generate(json, this.depthTextures(), ...this.size);
    const frame = parseFrame(json);
    airlight.setLight(frame);
    this.lastMedium = this.mediumJson();
    airlight.setMedium(this.lastMedium);
    camera.updateMatrixWorld();
    airlight.setCamera({ view: camera.matrixWorldInverse, projection: camera.projectionMatrix, flipY: false });
    const shadowUpdate = renderer.shadowMap.autoUpdate;
    renderer.shadowMap.autoUpdate = false;  // the passes below must not re-render shadow maps
    const background = scene.background, override = scene.overrideMaterial;
    try {
      airlight.render(() => {
        scene.background = null;
        scene.overrideMaterial = this.surfaceMaterial;
        renderer.render(scene, camera);
      });
    } finally {
      scene.background = background;
      scene.overrideMaterial = override;
      renderer.shadowMap.autoUpdate = shadowUpdate;
    }
  }

  // The copied maps the adaptive volume reads: one, or an omni light's six.
  depthTextures() {
    return this.type === 'omni' ? this.copies.map((t) => t.depthTexture) : this.copies[0].depthTexture;
  }

  // The shadow map's depth into this addon's own depth textures (a blit: three.js's depth texture
  // keeps its comparison mode for its own shadows; texelFetch needs it off).
  copyShadowMap() {
    const { renderer, gl, light } = this;
    const shadow = light.shadow, map = shadow.map;
    if (!map || !map.depthTexture)
      throw new Error('LightVolume: the light has no shadow map yet: call renderer.render(scene, camera) ' +
                      'before volume.render() (three.js renders shadow maps there)');
    if (renderer.state.buffers.depth.getReversed && renderer.state.buffers.depth.getReversed())
      throw new Error('LightVolume: a reversed depth buffer stores reversed shadow depths; lightvol reads window depth');
    const faces = this.type === 'omni' ? OMNI_FACES : 1;
    if (this.type === 'omni' && !map.isWebGLCubeRenderTarget)
      throw new Error('LightVolume: this point light\'s shadow map is not a cube map of depth (three.js r180 or later makes one)');
    const width = map.width, height = map.height, type = map.depthTexture.type;
    if (width < 2 || height < 2)
      throw new Error(`LightVolume: the shadow map is ${width}x${height}; a volume needs at least 2x2 texels`);
    const resized = !this.size || this.size[0] !== width || this.size[1] !== height ||
                    this.copies[0].depthTexture.type !== type;
    if (resized) this.allocate(width, height, type, faces);
    const state = renderer.state, properties = renderer.properties;
    let sources = properties.get(map).__webglFramebuffer;
    if (!sources) throw new Error('LightVolume: three.js has not made the shadow map\'s framebuffer yet');
    if (!map.isWebGLCubeRenderTarget) sources = [sources];
    const previous = renderer.getRenderTarget();
    for (let f = 0; f < faces; ++f) {
      let source = sources[f];
      if (Array.isArray(source)) source = source[0];
      state.bindFramebuffer(gl.READ_FRAMEBUFFER, source);
      state.bindFramebuffer(gl.DRAW_FRAMEBUFFER, properties.get(this.copies[f]).__webglFramebuffer);
      gl.blitFramebuffer(0, 0, width, height, 0, 0, width, height, gl.DEPTH_BUFFER_BIT, gl.NEAREST);
    }
    state.bindFramebuffer(gl.READ_FRAMEBUFFER, null);
    renderer.setRenderTarget(previous);
    if (resized) {
      const error = gl.getError();
      if (error !== gl.NO_ERROR)
        throw new Error(`LightVolume: copying the ${width}x${height} shadow map failed (WebGL error 0x${error.toString(16)}): ` +
                        'its depth format cannot be read');
    }
  }

  allocate(width, height, type, faces) {
    for (const t of this.copies) { t.depthTexture.dispose(); t.dispose(); }
    this.copies = [];
    for (let f = 0; f < faces; ++f) {
      const depth = new THREE.DepthTexture(width, height, type);
      depth.format = THREE.DepthFormat;
      depth.minFilter = depth.magFilter = THREE.NearestFilter;
      depth.compareFunction = null;
      const target = new THREE.WebGLRenderTarget(width, height, { depthTexture: depth, stencilBuffer: false });
      this.renderer.initRenderTarget(target);
      this.copies.push(target);
    }
    const maps = this.copies.map((t) => t.depthTexture);
    this.live.shadow_maps.value = Array.from({ length: OMNI_FACES }, (_, f) => maps[Math.min(f, maps.length - 1)]);
    this.size = [width, height];
    this.indicesFor = null;
  }

  // The live stage's uniforms (live_uniforms in src/lightvol/render/live_volume.cpp) and build's
  // triangles, for the light as it is now.
  setUniforms(json) {
    const [width, height] = this.size;
    const omni = this.type === 'omni';
    const camera = this.light.shadow.camera;
    const projection = camera.projectionMatrix.clone();
    const views = omni
        ? OMNI_LOOK.map((look, f) => toMatrix4(lookAt(json.position, look, OMNI_UP[f])))
        : [camera.matrixWorldInverse.clone()];
    const texels = views.map((v) => new Texels(v, projection, width, height, false, this.type === 'directional'));
    const u = this.live;
    u.live_size.value.set(width, height);
    const pitch = livePitch(width);
    u.live_pitch.value = pitch;
    u.live_depth.value = 0;
    u.live_flip_y.value = 0;
    u.live_type.value = omni ? 2 : this.type === 'directional' ? 1 : 0;
    u.live_standard.value = texels[0].standard ? 1 : 0;
    u.live_min_t.value = texels[0].minT;
    const e = texels[0].invProjection.elements;  // column-major: inv_p(i, j) = e[4j + i]
    u.live_ray_x.value.set(e[0], e[1], e[2], e[3]);
    u.live_ray_y.value.set(e[4], e[5], e[6], e[7]);
    u.live_near_0.value.set(e[12] - e[8], e[13] - e[9], e[14] - e[10], e[15] - e[11]);
    u.live_far_0.value.set(e[12] + e[8], e[13] + e[9], e[14] + e[10], e[15] + e[11]);
    texels.forEach((t, f) => u.live_eye_to_world.value[f].copy(t.toWorld));
    if (!omni) {
      const t = texels[0];
      u.live_apex.value.copy(t.apex());
      u.live_cap.value.copy(t.nearPoint(0, 0).add(t.nearPoint(width - 1, 0)).add(t.nearPoint(0, height - 1))
                             .add(t.nearPoint(width - 1, height - 1)).multiplyScalar(0.25));
    }
    // The triangles depend on the size and the windings only.
    const key = `${width}x${height}:${texels.map((t) => (t.standard ? 1 : 0)).join('')}`;
    if (this.indicesFor === key) return;
    if (this.adaptive) {  // made on the GPU each frame (render()); omni: its faces' windings and seams
      if (omni) {
        const small = views.map((v) => new Texels(v, projection, 2, 2, false, false));
        this.adaptive.setOmni(texels.map((t) => t.standard), omniAdjacency(small));
      }
      this.indicesFor = key;
      return;
    }
    let indices;
    if (omni) {
      const small = views.map((v) => new Texels(v, projection, 2, 2, false, false));
      indices = omniVolumeIndices(width, texels.map((t) => t.standard), omniAdjacency(small));
    } else {
      indices = staticVolumeIndices(this.type, width, height, texels[0].standard);
    }
    const faces = omni ? OMNI_FACES : 1;
    const drawn = cacheOrder(indices, width, height, faces);
    indices = drawn.indices;
    this.drawOrder = drawn;
    for (let i = 0; i < indices.length; ++i) indices[i] = drawVertexId(indices[i], width, height, pitch, faces);
    this.geometry.dispose();
    this.geometry.setIndex(new THREE.BufferAttribute(indices, 1));
    this.indicesFor = key;
  }

  // The static volume's triangles as drawn, in build's vertex numbering and order (tests: build's
  // indices, number for number): the index buffer, each id mapped back through the draw's pitch
  // and each triangle put back in build's place and corner order (cacheOrder).
  buildIndices() {
    const [width, height] = this.size, faces = this.type === 'omni' ? OMNI_FACES : 1;
    const pitch = this.live.live_pitch.value, drawn = this.geometry.index.array;
    const { order, turn } = this.drawOrder, out = new Uint32Array(drawn.length);
    for (let i = 0; i < order.length; ++i)
      for (let j = 0; j < 3; ++j)
        out[3 * order[i] + (turn[i] + j) % 3] = buildVertexId(drawn[3 * i + j], width, height, pitch, faces);
    return out;
  }

  // That frame's airlight, width × height floats, top row first.
  readAirlight() { return this.airlight.readAirlight(); }
  readSurface() { return this.airlight.readSurface(); }
  readFaceCounts() { return this.airlight.readFaceCounts(); }
  // lightvol's light JSON of the map the last render() used, and the medium it used.
  lightJson() { return this.lastLight; }
  lastMediumJson() { return this.lastMedium; }

  // The shadow map the last render() used, in its window depth, as lightvol reads images: W × H
  // floats, top row first (omni: the six faces +X −X +Y −Y +Z −Z one under the other, W × 6W).
  readShadowMap() {
    const { renderer, gl } = this;
    const [width, height] = this.size;
    const target = new THREE.WebGLRenderTarget(width, height, {
      type: THREE.FloatType, format: THREE.RedFormat, depthBuffer: false,
      minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter });
    const previous = renderer.getRenderTarget();
    const out = new Float32Array(width * height * this.copies.length);
    const rgba = new Float32Array(width * height * 4);
    const camera = new THREE.Camera();
    this.copies.forEach((copy, f) => {
      this.readMaterial.uniforms.map.value = copy.depthTexture;
      renderer.setRenderTarget(target);
      renderer.render(this.readScene, camera);
      gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, rgba);
      for (let r = 0; r < height; ++r)
        for (let c = 0; c < width; ++c)
          out[(f * height + r) * width + c] = rgba[((height - 1 - r) * width + c) * 4];
    });
    renderer.setRenderTarget(previous);
    target.dispose();
    return out;
  }

  // For tests, never in a frame: the volume's vertices as the GPU makes them from the map the last
  // render() used (xyz floats, world space, build's order), captured by transform feedback from
  // the same LIGHTVOL_LIVE_VOLUME_VERTEX stage with the same uniforms and read back.
  readPositions() {
    const { gl, renderer } = this;
    const u = this.live, props = renderer.properties;
    if (!this.captureProgram) {
      const shader = (type, source) => {
        const s = gl.createShader(type);
        gl.shaderSource(s, `#version 300 es\n${source}`);
        gl.compileShader(s);
        if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(`LightVolume: ${gl.getShaderInfoLog(s)}`);
        return s;
      };
      const program = gl.createProgram();
      gl.attachShader(program, shader(gl.VERTEX_SHADER, stageSource(`${this.liveDefines()}${this.glsl}`,
                                                                    'LIGHTVOL_LIVE_VOLUME_VERTEX')));
      gl.attachShader(program, shader(gl.FRAGMENT_SHADER,
                                      'precision highp float;\nout vec4 colour;\nvoid main() { colour = vec4(0.0); }\n'));
      gl.transformFeedbackVaryings(program, ['world'], gl.INTERLEAVED_ATTRIBS);
      gl.linkProgram(program);
      if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`LightVolume: ${gl.getProgramInfoLog(program)}`);
      this.captureProgram = program;
    }
    const program = this.captureProgram;
    const [width, height] = this.size;
    const faces = this.type === 'omni' ? OMNI_FACES : 1, pitch = u.live_pitch.value;
    const vertices = staticVolumeCounts(this.type, width, height).vertices;
    // Every id of the draw's numbering (the unused columns too), then build's vertices picked out.
    const n = drawVertexId(vertices - 1, width, height, pitch, faces) + 1;
    renderer.resetState();
    gl.useProgram(program);
    const at = (name) => gl.getUniformLocation(program, name);
    gl.uniform2i(at('live_size'), width, height);
    gl.uniform1i(at('live_pitch'), pitch);
    for (const name of ['live_flip_y', 'live_depth', 'live_type', 'live_standard']) gl.uniform1i(at(name), u[name].value);
    gl.uniform1f(at('live_min_t'), u.live_min_t.value);
    for (const name of ['live_ray_x', 'live_ray_y', 'live_near_0', 'live_far_0']) gl.uniform4fv(at(name), u[name].value.toArray());
    const matrices = new Float32Array(16 * OMNI_FACES);
    u.live_eye_to_world.value.forEach((m, f) => matrices.set(m.elements, 16 * f));
    gl.uniformMatrix4fv(at('live_eye_to_world'), false, matrices);
    gl.uniform3fv(at('live_apex'), u.live_apex.value.toArray());
    gl.uniform3fv(at('live_cap'), u.live_cap.value.toArray());
    gl.uniformMatrix4fv(at('view_projection'), false, new THREE.Matrix4().elements);
    u.shadow_maps.value.forEach((texture, f) => {
      gl.activeTexture(gl.TEXTURE0 + f);
      gl.bindTexture(gl.TEXTURE_2D, props.get(texture).__webglTexture);
      gl.uniform1i(at(`shadow_maps[${f}]`), f);
    });
    const buffer = gl.createBuffer(), feedback = gl.createTransformFeedback();
    gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, buffer);
    gl.bufferData(gl.TRANSFORM_FEEDBACK_BUFFER, 12 * n, gl.STREAM_READ);
    gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, null);
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, feedback);
    gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, buffer);
    gl.enable(gl.RASTERIZER_DISCARD);
    gl.beginTransformFeedback(gl.POINTS);
    gl.drawArrays(gl.POINTS, 0, n);
    gl.endTransformFeedback();
    gl.disable(gl.RASTERIZER_DISCARD);
    gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
    const drawn = new Float32Array(3 * n);
    gl.bindBuffer(gl.COPY_READ_BUFFER, buffer);
    gl.getBufferSubData(gl.COPY_READ_BUFFER, 0, drawn);
    const out = new Float32Array(3 * vertices);
    for (let v = 0; v < vertices; ++v) {
      const id = drawVertexId(v, width, height, pitch, faces);
      out.set(drawn.subarray(3 * id, 3 * id + 3), 3 * v);
    }
    gl.bindBuffer(gl.COPY_READ_BUFFER, null);
    gl.deleteBuffer(buffer);
    gl.deleteTransformFeedback(feedback);
    renderer.resetState();
    return out;
  }

  // For tests, never in a frame (adaptive volumes): the last frame's triangles as drawn, read back
  // by transform feedback (AdaptiveVolume.readTriangles: [kind, col, row] × 3 each), and whether
  // its fix-up rounds converged.
  readTriangles() { return this.adaptive.readTriangles(); }
  converged() { return this.adaptive.converged(); }

  dispose() {
    if (this.adaptive) this.adaptive.dispose();
    for (const t of this.copies) { t.depthTexture.dispose(); t.dispose(); }
    this.geometry.dispose();
    this.volumeMaterial.dispose();
    this.surfaceMaterial.dispose();
    this.readMaterial.dispose();
  }
}
