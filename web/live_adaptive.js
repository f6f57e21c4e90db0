// The adaptive light volume of LightVolume (light_volume.js, option maxError; docs/web.md): `lightvol
// build --adaptive --tessellation quadtree`'s volume of the frame's shadow map, made on the GPU every
// frame in WebGL2 by shaders/live_adaptive_webgl.glsl. WebGL2 has no compute shaders, so the error
// pyramid, the 2:1 balance and the fix-up rounds are fragment passes into an R8UI atlas of the
// quadtree's cells (one level a pass, each written to a scratch atlas and blitted back), a last
// pass writes what each cell emits and its triangle count into the base of a count pyramid (a
// histopyramid: an R32UI base and an RGBA32UI atlas of its levels, each texel its four children's
// counts, a fragment pass a level), and two draws with no vertex buffer
// emit the triangles: one of 3 vertices a triangle, each finding its cell by descending the
// pyramid, and one of 9 vertices a border ring edge (the closing). The grid draw's vertex count is
// the pyramid's top texel, read back (one integer a frame, count: 'readback', the default), or
// the static volume's triangle count, an upper bound, its surplus vertices degenerate (count:
// 'bound': no read-back). docs/web.md says which costs what. A point light's six faces share the
// atlas (each level's rectangle six faces tall), with build's seam rounds (a pass forcing the
// border vertices the last round's union asked for, a pass uniting each seam's two borders) and an
// omni closing draw (the seams' strips and the corners).
import * as THREE from 'three';

const PREFIX = 'precision highp float;\nprecision highp int;\nprecision highp sampler2D;\n';
const FULL_SCREEN = '#version 300 es\nvoid main() {\n' +
                    '  gl_Position = vec4(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0, 0.0, 1.0);\n}\n';
const CLOSE_VERTICES = 9;
const MAX_ROUNDS = 63;      // fix-up rounds a frame, at most   // 3 triangles: a directional ring edge's walls and cap
const SHADER_URL = new URL('../shaders/live_adaptive_webgl.glsl', import.meta.url).href;

// The largest float <= e.
function floatFloor(e) {
  const f = new Float32Array([e]);
  if (f[0] > e) {
    const bits = new Int32Array(f.buffer);
    bits[0] += f[0] > 0 ? -1 : 1;
    if (f[0] === 0) f[0] = -Number.MIN_VALUE;
  }
  return f[0];
}

// An integer render target: R8UI (the cells' states), R32UI or RGBA32UI (the count pyramid).
function integerTarget(width, height, internalFormat = 'R8UI') {
  const t = new THREE.WebGLRenderTarget(width, height, {
    format: internalFormat === 'RGBA32UI' ? THREE.RGBAIntegerFormat : THREE.RedIntegerFormat,
    type: internalFormat === 'R8UI' ? THREE.UnsignedByteType : THREE.UnsignedIntType, depthBuffer: false,
    minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, generateMipmaps: false });
  t.texture.internalFormat = internalFormat;
  return t;
}

// Sets a raw program's uniforms from three.js-style uniform objects ({ value }), textures by
// three.js's own handles; `units` counts texture units from 0.
function applyUniforms(gl, renderer, program, uniforms) {
  let unit = 0;
  const count = gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS);
  for (let k = 0; k < count; ++k) {
    const info = gl.getActiveUniform(program, k);
    const name = info.name.replace(/\[0\]$/, '');
    const u = uniforms[name];
    if (!u) continue;
    const at = gl.getUniformLocation(program, info.name);
    const v = u.value;
    switch (info.type) {
      case gl.FLOAT: gl.uniform1f(at, v); break;
      case gl.INT: case gl.BOOL:
        if (info.size > 1) gl.uniform1iv(at, Int32Array.from(v));
        else gl.uniform1i(at, v);
        break;
      case gl.INT_VEC2: gl.uniform2i(at, v.x ?? v[0], v.y ?? v[1]); break;
      case gl.FLOAT_VEC2: gl.uniform2f(at, v.x, v.y); break;
      case gl.FLOAT_VEC3: gl.uniform3f(at, v.x, v.y, v.z); break;
      case gl.FLOAT_VEC4: gl.uniform4f(at, v.x, v.y, v.z, v.w); break;
      case gl.FLOAT_MAT4: {
        const list = Array.isArray(v) ? v : [v];
        const data = new Float32Array(16 * list.length);
        list.forEach((m, f) => data.set(m.elements, 16 * f));
        gl.uniformMatrix4fv(at, false, data);
        break;
      }
      case gl.SAMPLER_2D: case gl.UNSIGNED_INT_SAMPLER_2D: {
        const list = Array.isArray(v) ? v : [v];
        const units = [];
        for (let i = 0; i < info.size; ++i) {
          const texture = list[Math.min(i, list.length - 1)];
          gl.activeTexture(gl.TEXTURE0 + unit);
          gl.bindTexture(gl.TEXTURE_2D, texture.isTexture ? renderer.properties.get(texture).__webglTexture : texture);
          units.push(unit++);
        }
        gl.uniform1iv(at, Int32Array.from(units));
        break;
      }
      default: throw new Error(`LightVolume: internal error: uniform ${info.name} of type 0x${info.type.toString(16)}`);
    }
  }
}

// An omni light's face f as lightvol sees it, in double: view omni_face_view (look_at) and
// projection perspective(90°, 1, near, far), rows. The measure's per-texel constants are the same
// for the six faces (a rigid view changes neither G nor w), so face 0's serve them all.
export function omniFace(json, f) {
  const look = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]][f];
  const up = [[0, -1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0], [0, -1, 0]][f];
  const norm = (v) => { const l = Math.hypot(...v); return v.map((x) => x / l); };
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const e = json.position, fw = norm(look), sd = norm(cross(fw, up)), uu = cross(sd, fw);
  const view = [[...sd, -dot(sd, e)], [...uu, -dot(uu, e)], [-fw[0], -fw[1], -fw[2], dot(fw, e)], [0, 0, 0, 1]];
  const t = 1 / Math.tan(90 * Math.PI / 360), { near, far } = json;
  const projection = [[t, 0, 0, 0], [0, t, 0, 0], [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]];
  return { type: 'omni', view, projection };
}

export class AdaptiveVolume {
  // The text of shaders/live_adaptive_webgl.glsl (beside shaders/airlight.glsl).
  static async loadShader(url = SHADER_URL) {
    const response = await fetch(url);
    if (!response.ok) throw new Error(`LightVolume: ${url}: HTTP ${response.status}`);
    return response.text();
  }

  // renderer: three's WebGLRenderer; glsl: shaders/airlight.glsl; adaptiveGlsl: this file's
  // shader; maxError: E (world units along the texel rays, as build's --max-error); count: how the
  // grid draw is sized, 'readback' (the pyramid's top texel, read back each frame: a sync point) or
  // 'bound' (the static volume's triangle count, no read-back); rounds: the fix-up rounds a frame
  // runs before it looks (readback: default 1, then one more round at a time while the last one
  // split a cell, so every frame converges; bound: default 4 and no more, build's quadtree needs
  // at most 1 on the demo's maps; converged() tells).
  // live: LightVolume's live-stage uniforms; volumeUniforms: the volume pass's.
  // faces: 6 for a point light (omni: the six cube faces' quadtrees in one atlas, with build's seam
  // rounds and omni closing; setOmni() gives the faces' windings and adjacency), else 1;
  // seamRounds: with count 'bound', the seam rounds a frame runs (default 8; readback: until the
  // seams agree, one read-back a round).
  constructor(renderer, glsl, adaptiveGlsl, { maxError, rounds, count = 'readback', live, volumeUniforms, volumeState, fragmentShader,
                                              faces = 1, seamRounds = 8 }) {
    if (!(Number.isFinite(maxError) && maxError >= 0))
      throw new Error(`LightVolume: maxError: expected a finite number >= 0, got ${maxError}`);
    rounds ??= count === 'readback' ? 1 : 4;
    if (!(Number.isInteger(rounds) && rounds >= 1 && rounds <= MAX_ROUNDS))
      throw new Error(`LightVolume: rounds: expected an integer from 1 to 63, got ${rounds}`);
    if (count !== 'readback' && count !== 'bound')
      throw new Error(`LightVolume: count: expected 'readback' or 'bound', got ${count}`);
    if (!adaptiveGlsl) throw new Error('LightVolume: options.adaptiveGlsl is empty (LightVolume.loadAdaptiveShader() gives it)');
    this.renderer = renderer;
    this.gl = renderer.getContext();
    this.glsl = glsl;
    this.adaptiveGlsl = adaptiveGlsl;
    this.maxError = maxError;
    this.rounds = rounds;
    this.count = count;
    this.live = live;
    this.faces = faces;
    this.omni = faces === 6;
    this.seamRounds = seamRounds;
    this.key = null;
    this.raysKey = null;
    const zeros = () => new Array(16).fill(0);
    this.u = {
      lva_map: { value: new THREE.Vector2(2, 2) },
      lva_top: { value: 1 },
      lva_nx: { value: zeros() }, lva_ny: { value: zeros() },
      lva_ox: { value: zeros() }, lva_oy: { value: zeros() },
      lva_first: { value: new Array(17).fill(0) },
      lva_level: { value: 1 }, lva_round: { value: 0 },
      lva_uniform: { value: 0 }, lva_scale: { value: 1 },
      lva_bound: { value: floatFloor(maxError) },
      lva_base: { value: new THREE.Vector2(1, 1) }, lva_levels: { value: 0 },
      lva_splits: { value: null }, lva_fails: { value: null },
      lva_px: { value: new Array(17).fill(0) }, lva_py: { value: new Array(17).fill(0) },
      lva_cells: { value: null }, lva_pyramid: { value: null },
      lva_depth: { value: null }, lva_rays: { value: null },
      lva_faces: { value: faces }, lva_standard: { value: 63 }, lva_dirty: { value: 63 },
      lva_forced: { value: null }, lva_union: { value: null }, lva_threshold: { value: null },
      lva_across: { value: new Array(24).fill(0) },
      lva_seam: { value: new Array(72).fill(0) }, lva_corner: { value: new Array(72).fill(0) },
    };
    this.define = this.omni ? '#define LVA_OMNI\n' : '';
    this.passes = {};
    for (const stage of ['OWN', 'BALANCE', 'TEST', 'CODE', 'REDUCE', ...(this.omni ? ['FORCE', 'UNITE'] : [])])
      this.passes[stage] = this.program(FULL_SCREEN, `#version 300 es\n${PREFIX}${this.define}#define LVA_${stage}\n${adaptiveGlsl}`);
    this.vao = this.gl.createVertexArray();
    const material = (stage) => new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: this.emitSource(stage),
      fragmentShader,
      uniforms: { ...volumeUniforms, ...live, ...this.u },
      ...volumeState,
    });
    // No attributes: three.js draws drawRange.count vertices.
    this.gridGeometry = new THREE.BufferGeometry();
    this.closeGeometry = new THREE.BufferGeometry();
    this.gridGeometry.setDrawRange(0, 0);
    this.closeGeometry.setDrawRange(0, 0);
    this.gridMaterial = material('GRID');
    this.closeMaterial = material('CLOSE');
    this.meshes = [new THREE.Mesh(this.gridGeometry, this.gridMaterial),
                   new THREE.Mesh(this.closeGeometry, this.closeMaterial)];
    for (const m of this.meshes) m.frustumCulled = false;
    this.targets = [];
  }

  emitSource(stage) {
    return `${PREFIX}${this.define}#define LIGHTVOL_LIVE_COMMON\n#define LVA_EMIT_${stage}\n${this.glsl}\n${this.adaptiveGlsl}`;
  }

  // Omni: the faces' windings (standard[f]: face f's grid wound as the standard one) and the cube's
  // adjacency (light_volume.js omniAdjacency: seams { face, border, reversed, flip }, corners
  // { face, lastCol, lastRow }), as build's omni_adjacency gives them.
  setOmni(standard, adjacency) {
    const side = { top: 0, right: 1, bottom: 2, left: 3 };
    const u = this.u;
    u.lva_standard.value = standard.reduce((m, s, f) => m | (s ? 1 << f : 0), 0);
    adjacency.seams.forEach((seam, k) => {
      const [a, b] = seam.face, [sa, sb] = seam.border.map((x) => side[x]);
      u.lva_seam.value.splice(6 * k, 6, a, sa, b, sb, seam.reversed ? 1 : 0, seam.flip ? 1 : 0);
      u.lva_across.value[4 * a + sa] = 8 * b + 2 * sb + (seam.reversed ? 1 : 0);
      u.lva_across.value[4 * b + sb] = 8 * a + 2 * sa + (seam.reversed ? 1 : 0);
    });
    adjacency.corners.forEach((c, k) => {
      for (let m = 0; m < 3; ++m)
        u.lva_corner.value.splice(9 * k + 3 * m, 3, c.face[m], c.lastCol[m] ? 1 : 0, c.lastRow[m] ? 1 : 0);
    });
  }

  program(vertex, fragment, feedback = null) {
    const gl = this.gl;
    const shader = (type, source) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, source);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS))
        throw new Error(`LightVolume: the adaptive volume's shader: ${gl.getShaderInfoLog(s)}`);
      return s;
    };
    const p = gl.createProgram();
    gl.attachShader(p, shader(gl.VERTEX_SHADER, vertex));
    gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fragment));
    if (feedback) gl.transformFeedbackVaryings(p, feedback, gl.INTERLEAVED_ATTRIBS);
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS))
      throw new Error(`LightVolume: the adaptive volume's program: ${gl.getProgramInfoLog(p)}`);
    return p;
  }

  // The quadtree of a W × H map (detail::Quadtree: levels 1..top, at least one) and its atlas:
  // level 1 at (0, 0), levels 2..top stacked to its right; each level a rectangle of nx × faces·ny
  // cells, face f's from row f·ny.
  resize(width, height) {
    if (this.omni && width !== height) throw new Error(`LightVolume: a point light's faces are ${width}x${height}: not square`);
    const faces = this.faces;
    const key = `${width}x${height}`;
    if (this.key === key) return;
    this.key = key;
    this.raysKey = null;
    const cw = width - 1, ch = height - 1;
    let top = 0;
    while ((1 << top) < Math.max(cw, ch)) ++top;
    top = Math.max(top, 1);
    if (top > 15) throw new Error('LightVolume: adaptive volumes take maps of at most 32769 texels a side');
    const u = this.u;
    u.lva_map.value.set(width, height);
    u.lva_top.value = top;
    let cells = 0, y = 0;
    for (let L = 1; L <= top; ++L) {
      const nx = (cw + (1 << L) - 1) >> L, ny = (ch + (1 << L) - 1) >> L;
      u.lva_nx.value[L] = nx;
      u.lva_ny.value[L] = ny;
      u.lva_first.value[L] = cells;
      cells += nx * ny;
      if (L === 1) {
        u.lva_ox.value[L] = 0;
        u.lva_oy.value[L] = 0;
      } else {
        u.lva_ox.value[L] = u.lva_nx.value[1];
        u.lva_oy.value[L] = y;
        y += faces * ny;
      }
    }
    u.lva_first.value[top + 1] = cells;
    cells *= faces;
    this.cells = cells;
    this.top = top;
    this.atlas = [u.lva_nx.value[1] + (top >= 2 ? u.lva_nx.value[2] : 0), Math.max(faces * u.lva_ny.value[1], y)];
    this.column = [u.lva_nx.value[1], 0, top >= 2 ? u.lva_nx.value[2] : 0, y];  // levels 2..top
    for (const t of this.targets) t.dispose();
    const [aw, ah] = this.atlas;
    this.splits = integerTarget(aw, ah);
    this.scratch = integerTarget(aw, ah);
    this.fails = integerTarget(aw, ah);
    // The count pyramid: a base of 2^a × 2^b texels (b = a or a − 1, at least 2 × 1) holding every
    // cell, level k max(1, base >> k) texels a side, up to the top's 1 × 1; levels 1..top in one
    // atlas (level 1 at (0, 0), the others stacked to its right), drawn through a scratch atlas.
    let bw = 2, bh = 1;
    while (bw * bh < cells) {
      if (bw === bh) bw *= 2;
      else bh *= 2;
    }
    let levels = 0;
    while ((Math.max(bw, bh) >> levels) > 1) ++levels;
    const size = (k) => [Math.max(1, bw >> k), Math.max(1, bh >> k)];
    let py = 0;
    for (let k = 1; k <= levels; ++k) {
      u.lva_px.value[k] = k === 1 ? 0 : size(1)[0];
      u.lva_py.value[k] = k === 1 ? 0 : py;
      if (k > 1) py += size(k)[1];
    }
    this.pyramidAtlas = [size(1)[0] + (levels >= 2 ? size(2)[0] : 0), Math.max(size(1)[1], py)];
    this.cellsTarget = integerTarget(bw, bh, 'R32UI');
    this.pyramid = integerTarget(...this.pyramidAtlas, 'RGBA32UI');
    this.pyramidScratch = integerTarget(...this.pyramidAtlas, 'RGBA32UI');
    this.targets = [this.splits, this.scratch, this.fails, this.cellsTarget, this.pyramid, this.pyramidScratch];
    if (this.omni) {
      this.threshold = integerTarget(aw, ah);
      this.forced = integerTarget(width, 4 * faces);
      this.union = integerTarget(width, 4 * faces);
      this.targets.push(this.threshold, this.forced, this.union);
      u.lva_threshold.value = this.threshold.texture;
      u.lva_forced.value = this.forced.texture;
      u.lva_union.value = this.union.texture;
    }
    for (const t of this.targets) this.renderer.initRenderTarget(t);
    u.lva_splits.value = this.splits.texture;
    u.lva_fails.value = this.fails.texture;
    u.lva_cells.value = this.cellsTarget.texture;
    u.lva_pyramid.value = this.pyramid.texture;
    u.lva_base.value.set(bw, bh);
    u.lva_levels.value = levels;
    this.base = [bw, bh];
    this.levels = levels;
    this.perimeter = 2 * cw + 2 * ch;
    this.bound = faces * 2 * cw * ch;  // the static volume's grid triangles: no quadtree has more
    // The closing's vertices: 9 a border ring edge; omni: 6 a unit edge of each of the 12 seams,
    // 3 a corner.
    this.closeVertices = this.omni ? 72 * cw + 24 : CLOSE_VERTICES * this.perimeter;
    this.gridGeometry.setDrawRange(0, 3 * this.bound);
    this.closeGeometry.setDrawRange(0, this.closeVertices);
  }

  // The measure's per-texel constants (TexelDepths::create, in double): orthographic lights a
  // uniform scale; perspective ones K = G / w1² and d∞ = −w0 / w1 as two floats (the GLSL file).
  prepareRays(json, width, height) {
    if (json.type === 'omni') json = omniFace(json, 0);
    const key = `${width}x${height}:${json.projection.flat().join(',')}`;
    if (this.raysKey === key) return;
    this.raysKey = key;
    const fromRows = (r) => new THREE.Matrix4().set(...r.flat());
    const m = fromRows(json.view).invert().multiply(fromRows(json.projection).invert());
    const e = m.elements, at = (r, c) => e[4 * c + r];
    const h1 = [0, 1, 2, 3].map((k) => 2 * at(k, 2));
    const x0 = 2 * 0.5 / width - 1, y0 = -(2 * 0.5 / height - 1);
    const w0c = at(3, 0) * x0 + at(3, 1) * y0 - at(3, 2) + at(3, 3);
    const u = this.u;
    u.lva_uniform.value = at(3, 0) === 0 && at(3, 1) === 0 && h1[3] === 0 ? 1 : 0;
    if (u.lva_uniform.value) {
      u.lva_scale.value = Math.hypot(h1[0], h1[1], h1[2]) / Math.abs(w0c);
      if (!this.rays) {
        this.rays = new THREE.DataTexture(new Float32Array(4), 1, 1, THREE.RGBAFormat, THREE.FloatType);
        this.rays.needsUpdate = true;
        this.renderer.initTexture(this.rays);
      }
      u.lva_rays.value = this.rays;
      return;
    }
    const data = new Float32Array(4 * width * height);
    const w1 = h1[3];
    for (let r = 0; r < height; ++r) {
      const y = -(2 * (r + 0.5) / height - 1);
      for (let c = 0; c < width; ++c) {
        const x = 2 * (c + 0.5) / width - 1;
        const h0 = [0, 1, 2, 3].map((k) => at(k, 0) * x + at(k, 1) * y - at(k, 2) + at(k, 3));
        const g = Math.hypot(h1[0] * h0[3] - h0[0] * h1[3], h1[1] * h0[3] - h0[1] * h1[3], h1[2] * h0[3] - h0[2] * h1[3]);
        const dInf = -h0[3] / w1, hi = Math.fround(dInf);
        data.set([g / (w1 * w1), hi, dInf - hi, 0], 4 * (r * width + c));
      }
    }
    if (this.rays) this.rays.dispose();
    this.rays = new THREE.DataTexture(data, width, height, THREE.RGBAFormat, THREE.FloatType);
    this.rays.minFilter = this.rays.magFilter = THREE.NearestFilter;
    this.rays.needsUpdate = true;
    this.renderer.initTexture(this.rays);
    u.lva_rays.value = this.rays;
  }

  // The frame's quadtree, from `depth` (the copied shadow map, a THREE.DepthTexture; omni: the six
  // faces', an array) of light JSON `json`: after LightVolume set the live uniforms, before the
  // volume is drawn.
  generate(json, depth, width, height) {
    const { gl, renderer, u } = this;
    this.resize(width, height);
    this.prepareRays(json, width, height);
    u.lva_depth.value = depth;
    const props = renderer.properties;
    const fbo = (t) => props.get(t).__webglFramebuffer;
    const clear = (t) => {
      gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, fbo(t));
      gl.clearBufferuiv(gl.COLOR, 0, new Uint32Array(4));
    };
    const copy = (from, to, [x, y, w, h]) => {
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, fbo(from));
      gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, fbo(to));
      gl.blitFramebuffer(x, y, x + w, y + h, x, y, x + w, y + h, gl.COLOR_BUFFER_BIT, gl.NEAREST);
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, null);
    };
    renderer.resetState();
    gl.bindVertexArray(this.vao);
    clear(this.splits);
    const run = (stage, target, [x, y, w, h], back) => {
      const p = this.passes[stage];
      gl.useProgram(p);
      applyUniforms(gl, renderer, p, u);
      gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, fbo(target));
      gl.viewport(x, y, w, h);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      if (back) copy(target, back, [x, y, w, h]);
    };
    const faces = this.faces;
    const level = (L) => [u.lva_ox.value[L], u.lva_oy.value[L], u.lva_nx.value[L], faces * u.lva_ny.value[L]];
    const balance = (round) => {
      u.lva_round.value = round;
      for (let L = 2; L <= this.top; ++L) {
        u.lva_level.value = L;
        run('BALANCE', this.scratch, level(L), this.splits);
      }
    };
    for (let L = 1; L <= this.top; ++L) {
      u.lva_level.value = L;
      run('OWN', this.scratch, level(L), this.splits);
    }
    const fixup = (round) => {
      u.lva_round.value = round;
      run('TEST', this.fails, this.column, null);
      balance(round);
    };
    const whole = [0, 0, ...this.atlas];
    const forced = [0, 0, width, 4 * faces];
    let round = 0, seamRound = 0;
    // Omni: a seam round tessellates every face from its threshold with the border vertices the
    // last round's union forced (lva_forced; none in the first), as build's OmniRefinement::build
    // does the faces it marked dirty (the others come out as they were: the same input).
    const tessellate = (dirty = 63) => {
      if (this.omni) {
        ++seamRound;
        u.lva_dirty.value = dirty;
        run('FORCE', this.scratch, whole, this.splits);
      }
      balance(0);
      clear(this.fails);
      round = 0;
      while (round < this.rounds && this.top >= 2) fixup(++round);
    };
    const unite = () => { if (this.omni) run('UNITE', this.union, forced, null); };
    if (this.omni) {
      copy(this.splits, this.threshold, whole);
      clear(this.forced);
      clear(this.union);
    }
    // Omni, after a read-back that found a seam lacking vertices (so no further wait): the sides
    // that lack one (3 in lva_union) take the union as their forced vertices (a row copied into
    // lva_forced), and their faces are re-tessellated, as build's unite_seams and dirty faces.
    // count 'bound' reads nothing: every side takes the union and every face is re-tessellated.
    const lacking = () => {
      if (this.count === 'bound') {
        copy(this.union, this.forced, forced);
        return 63;
      }
      const w = width, out = new Uint32Array(4 * w * 24);
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, fbo(this.union));
      gl.readPixels(0, 0, w, 24, gl.RGBA_INTEGER, gl.UNSIGNED_INT, out);
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, null);
      let dirty = 0;
      for (let row = 0; row < 24; ++row) {
        let lacks = false;
        for (let k = 0; k < w && !lacks; ++k) lacks = out[4 * (row * w + k)] === 3;
        if (!lacks) continue;
        dirty |= 1 << (row >> 2);
        copy(this.union, this.forced, [0, row, w, 1]);
      }
      return dirty;
    };
    tessellate();
    unite();
    // The count pyramid, from the cells' codes up to its top.
    const pyramidLevel = (k) => [u.lva_px.value[k], u.lva_py.value[k], Math.max(1, this.base[0] >> k),
                                 Math.max(1, this.base[1] >> k)];
    const pyramid = (k) => {
      u.lva_level.value = k;
      if (k === 0) run('CODE', this.cellsTarget, [0, 0, ...this.base], null);
      else run('REDUCE', this.pyramidScratch, pyramidLevel(k), this.pyramid);
    };
    const build = () => {
      for (let k = 0; k <= this.levels; ++k) pyramid(k);
    };
    // The top texel: its children's triangles (bit 31: the last fix-up round split a cell below;
    // bit 30, omni: a seam's borders did not agree).
    const top = () => {
      const out = new Uint32Array(4);
      const [x, y] = pyramidLevel(this.levels);
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, fbo(this.pyramid));
      gl.readPixels(x, y, 1, 1, gl.RGBA_INTEGER, gl.UNSIGNED_INT, out);
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, null);
      let triangles = 0, mark = 0, seam = 0;
      for (const v of out) {
        triangles += v & 0x3fffffff;
        mark |= v >>> 31;
        seam |= (v >>> 30) & 1;
      }
      return [triangles, mark, seam];
    };
    if (this.count === 'bound') {
      while (seamRound < this.seamRounds && this.omni) {
        tessellate(lacking());
        unite();
      }
    }
    build();
    if (this.count === 'readback') {
      let [triangles, mark, seam] = top();
      // The last round split cells whose new leaves no round has tested: one more round, until a
      // round splits nothing; then (omni) while a seam lacks vertices, another seam round.
      for (;;) {
        if (mark !== 0 && round < MAX_ROUNDS) fixup(++round);
        else if (seam !== 0 && seamRound < 4 * width + 4) tessellate(lacking());
        else break;
        unite();
        build();
        [triangles, mark, seam] = top();
      }
      this.gridTriangles = triangles;
      this.gridGeometry.setDrawRange(0, 3 * triangles);
    }
    this.roundsRun = round;
    this.seamRoundsRun = seamRound;
    gl.bindVertexArray(null);
    renderer.resetState();
  }

  // For tests, never in a frame: whether the last frame's fix-up converged (its last round split
  // nothing), read back.
  converged() {
    const { gl, renderer } = this;
    const [x, y, w, h] = this.column;
    if (w === 0 || h === 0) return true;
    const out = new Uint32Array(4 * w * h);
    renderer.resetState();
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, renderer.properties.get(this.fails).__webglFramebuffer);
    gl.readPixels(x, y, w, h, gl.RGBA_INTEGER, gl.UNSIGNED_INT, out);
    renderer.resetState();
    for (let k = 0; k < out.length; k += 4) if (out[k] !== 0) return false;
    if (this.omni) {  // and every seam's two borders agree
      const w = this.u.lva_map.value.x, h = 24;
      const seams = new Uint32Array(4 * w * h);
      renderer.resetState();
      gl.bindFramebuffer(gl.READ_FRAMEBUFFER, renderer.properties.get(this.union).__webglFramebuffer);
      gl.readPixels(0, 0, w, h, gl.RGBA_INTEGER, gl.UNSIGNED_INT, seams);
      renderer.resetState();
      for (let k = 0; k < seams.length; k += 4) if (seams[k] === 3) return false;
    }
    return true;
  }

  // For tests, never in a frame: the last frame's triangles as the emission draws make them, by
  // transform feedback of the same vertex stages with the same uniforms: an array of triangles,
  // each three [kind, col, row] (kind 1 grid vertex of texel (col, row), 2 apex, 3 near-plane copy
  // of texel (col, row), 4 cap), the grid's first, wound as drawn.
  readTriangles(extraUniforms) {
    const { gl, renderer } = this;
    if (Math.max(...this.u.lva_map.value.toArray()) > 16384)
      throw new Error('LightVolume: readTriangles takes maps of at most 16384 texels a side');
    const fragment = `#version 300 es\n${PREFIX}out vec4 colour;\nvoid main() { colour = vec4(0.0); }\n`;
    if (!this.feedback)
      this.feedback = {
        GRID: this.program(`#version 300 es\n${this.emitSource('GRID')}`, fragment, ['lva_vertex']),
        CLOSE: this.program(`#version 300 es\n${this.emitSource('CLOSE')}`, fragment, ['lva_vertex']),
      };
    const uniforms = { ...this.live, ...this.u, view_projection: { value: new THREE.Matrix4() }, ...extraUniforms };
    const triangles = [];
    for (const [stage, n] of [['GRID', this.gridGeometry.drawRange.count], ['CLOSE', this.closeVertices]]) {
      const program = this.feedback[stage];
      renderer.resetState();
      gl.useProgram(program);
      applyUniforms(gl, renderer, program, uniforms);
      gl.bindVertexArray(this.vao);
      const buffer = gl.createBuffer(), feedback = gl.createTransformFeedback();
      gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, buffer);
      gl.bufferData(gl.TRANSFORM_FEEDBACK_BUFFER, 4 * Math.max(n, 3), gl.STREAM_READ);
      gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, null);
      gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, feedback);
      gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, buffer);
      gl.enable(gl.RASTERIZER_DISCARD);
      gl.beginTransformFeedback(gl.TRIANGLES);
      gl.drawArrays(gl.TRIANGLES, 0, n);
      gl.endTransformFeedback();
      gl.disable(gl.RASTERIZER_DISCARD);
      gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
      gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
      const out = new Uint32Array(n);
      gl.bindBuffer(gl.COPY_READ_BUFFER, buffer);
      gl.getBufferSubData(gl.COPY_READ_BUFFER, 0, out);
      gl.bindBuffer(gl.COPY_READ_BUFFER, null);
      gl.deleteBuffer(buffer);
      gl.deleteTransformFeedback(feedback);
      gl.bindVertexArray(null);
      const vertex = (v) => [v >>> 28, (v >>> 14) & 0x3fff, v & 0x3fff];
      for (let t = 0; t < n; t += 3) {
        if (out[t] === 0) continue;
        triangles.push([vertex(out[t]), vertex(out[t + 1]), vertex(out[t + 2])]);
      }
    }
    renderer.resetState();
    return triangles;
  }

  dispose() {
    for (const t of this.targets) t.dispose();
    if (this.rays) this.rays.dispose();
    this.gridGeometry.dispose();
    this.closeGeometry.dispose();
    this.gridMaterial.dispose();
    this.closeMaterial.dispose();
    const gl = this.gl;
    for (const p of Object.values(this.passes)) gl.deleteProgram(p);
    gl.deleteVertexArray(this.vao);
  }
}
