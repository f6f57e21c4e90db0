// lightvol's airlight in WebGL2 through three.js: the passes of shaders/airlight.glsl (the file
// itself, fetched and compiled with the WebGL2 prefix of docs/engines.md), the F(u, v) table, and
// lightvol's light, camera and medium descriptions turned into its uniforms.
import * as THREE from 'three';

// docs/engines.md: the WebGL2 version of shaders/airlight.glsl is the file behind this prefix and
// one #define naming the stage (three.js adds "#version 300 es" for GLSL3 raw shader materials).
const PREFIX = 'precision highp float;\nprecision highp int;\nprecision highp sampler2D;\n';
export function stageSource(glsl, stage, density = false) {
  return `${PREFIX}#define ${stage}\n${density ? '#define LIGHTVOL_DENSITY\n' : ''}${glsl}`;
}

// ---- lightvol's matrices (row-major arrays of 16, as in src/lightvol/core/math.cpp) -----------

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const normalize = (a) => { const l = Math.sqrt(dot(a, a)); return [a[0] / l, a[1] / l, a[2] / l]; };

export function lookAt(eye, direction, up) {
  const f = normalize(direction), s = normalize(cross(f, up)), u = cross(s, f);
  return [s[0], s[1], s[2], -dot(s, eye), u[0], u[1], u[2], -dot(u, eye),
          -f[0], -f[1], -f[2], dot(f, eye), 0, 0, 0, 1];
}
export function perspective(fovYDeg, aspect, near, far) {
  const f = 1 / Math.tan(fovYDeg * Math.PI / 360);
  return [f / aspect, 0, 0, 0, 0, f, 0, 0,
          0, 0, (far + near) / (near - far), 2 * far * near / (near - far), 0, 0, -1, 0];
}
export function orthographic(l, r, b, t, near, far) {
  return [2 / (r - l), 0, 0, -(r + l) / (r - l), 0, 2 / (t - b), 0, -(t + b) / (t - b),
          0, 0, -2 / (far - near), -(far + near) / (far - near), 0, 0, 0, 1];
}
const rowsToArray = (rows) => (rows.length === 4 ? rows.flat() : rows.slice());
export const toMatrix4 = (m) => new THREE.Matrix4().set(...m);

// A light or camera description (lightvol's JSON: geometric keys, or "view" and "projection")
// as {type, view, projection (THREE.Matrix4), position, direction, near, flip_y}.
export function parseFrame(json) {
  const type = json.type ?? 'spot';
  let view, projection;
  if (json.view) {
    view = toMatrix4(rowsToArray(json.view));
    projection = toMatrix4(rowsToArray(json.projection));
  } else if (type === 'omni') {
    const p = json.position;
    view = toMatrix4([1, 0, 0, -p[0], 0, 1, 0, -p[1], 0, 0, 1, -p[2], 0, 0, 0, 1]);
    projection = toMatrix4(perspective(90, 1, json.near, json.far));
  } else {
    view = toMatrix4(lookAt(json.position, json.direction, json.up));
    projection = toMatrix4(type === 'directional'
        ? orthographic(...json.ortho, json.near, json.far)
        : perspective(json.fov_y_deg, json.aspect ?? 1, json.near, json.far));
  }
  const inv = view.clone().invert();
  const position = new THREE.Vector3(0, 0, 0).applyMatrix4(inv);
  const direction = new THREE.Vector3(0, 0, -1).transformDirection(inv);
  const p = projection.elements;  // column-major: P[row][col] = p[col * 4 + row]
  const p22 = p[10], p23 = p[14];
  const perspectiveProjection = p[11] !== 0;
  const near = perspectiveProjection ? p23 / (p22 - 1) : (p23 + 1) / p22;
  return { type, view, projection, position, direction, near, perspective: perspectiveProjection,
           flipY: !!json.flip_y, width: json.width, height: json.height };
}

// ---- Sun et al.'s F(u, v) table, as sun_table() in src/lightvol/render/gl_volume.cpp ---------

export const TABLE = { rows: 512, cols: 1024, uMax: 32 };
export function sunTable() {
  const { rows, cols, uMax } = TABLE;
  const values = new Float32Array(rows * cols);
  const x = [0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363];
  const w = [0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763];
  const dv = 0.5 * Math.PI / (cols - 1);
  for (let i = 0; i < rows; ++i) {
    const a = i / (rows - 1), u = uMax * a * a;
    let sum = 0;
    for (let j = 1; j < cols; ++j) {
      const lo = (j - 1) * dv;
      for (let q = 0; q < 2; ++q) {
        const mid = lo + (q + 0.5) * 0.5 * dv, half = 0.25 * dv;
        for (let k = 0; k < 4; ++k)
          sum += half * w[k] * (Math.exp(-u * Math.tan(mid - half * x[k])) +
                                Math.exp(-u * Math.tan(mid + half * x[k])));
      }
      values[i * cols + j] = sum;
    }
  }
  const texture = new THREE.DataTexture(values, cols, rows, THREE.RedFormat, THREE.FloatType);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.needsUpdate = true;
  return texture;
}

// ---- the renderer ---------------------------------------------------------------------------

const PHASES = { isotropic: 0, hg: 1, schlick: 2 };

// Reduced resolution (AirlightRenderer's `resolution`). Down: each low pixel takes the surface
// distance of the full pixel under its centre. Up: each full pixel blends the 2 × 2 low pixels
// around it, weighted bilinearly and by 1 / (1 + (Δ/0.01)²), Δ the relative difference of their
// surface distances (3e38, nothing hit, matches only itself): where a surface edge crosses a
// block, a pixel takes its airlight from the low pixels of its own side. A low pixel whose face
// count is neither 0 nor 1 or whose airlight is negative (the rasterizer dropped or doubled a
// fragment of the closed volume: measured on SwiftShader, a few low pixels a frame) weighs a
// millionth.
const DOWNSAMPLE = `uniform sampler2D surface;
uniform vec2 scale;
layout(location = 0) out float distance_along_ray;
void main() {
  ivec2 p = min(ivec2(gl_FragCoord.xy * scale), textureSize(surface, 0) - 1);
  distance_along_ray = texelFetch(surface, p, 0).r;
}
`;
const UPSAMPLE = `uniform sampler2D surface;
uniform sampler2D low_surface;
uniform sampler2D low_airlight;
uniform sampler2D low_counts;
uniform vec2 scale;
layout(location = 0) out float airlight;
void main() {
  float t = texelFetch(surface, ivec2(gl_FragCoord.xy), 0).r;
  vec2 x = gl_FragCoord.xy / scale - 0.5;
  ivec2 i0 = ivec2(floor(x));
  vec2 f = x - vec2(i0);
  ivec2 last = textureSize(low_airlight, 0) - 1;
  float sum = 0.0, weights = 0.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 q = clamp(i0 + o, ivec2(0), last);
    float tq = texelFetch(low_surface, q, 0).r;
    float bilinear = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
    float far = max(t, tq), near = min(t, tq);
    float delta = far >= 1e38 ? (near >= 1e38 ? 0.0 : 1e4) : (far - near) / max(near, 1e-6);
    float count = texelFetch(low_counts, q, 0).g;
    float a = texelFetch(low_airlight, q, 0).r;
    float valid = (abs(count) < 0.5 || abs(count - 1.0) < 0.5) && a >= 0.0 ? 1.0 : 1e-6;
    float w = valid * (bilinear + 1e-6) / (1.0 + delta * delta * 1e4);
    sum += w * a;
    weights += w;
  }
  airlight = sum / weights;
}
`;

function floatTarget(width, height, format, depth, count = 1) {
  const target = new THREE.WebGLRenderTarget(width, height, {
    type: THREE.FloatType, format, depthBuffer: depth, stencilBuffer: false, count,
    minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, generateMipmaps: false,
  });
  return target;
}

// The composite both pages show, as lightvol demo's pictures: the lit scene (`scene`, a float
// texture) seen through the medium (× e^(−σt·t), t the distance in `surface`; with `through`, an
// R32F texture of each pixel's transmittance to its surface, × that instead: a medium of varying
// density, DensityGrid's throughTarget; × show_scene, 0 for no scene), plus the airlight (R32F) in
// the light's colour, × exposure, Reinhard x/(1+x), sRGB. sigmaT: a uniform object ({ value }),
// shared with the airlight's when it is the same medium.
export class Composite {
  constructor({ scene, airlight, surface, sigmaT, through = null, lightColour = [1, 1, 1] }) {
    this.uniforms = {
      scene_color: { value: scene }, airlight: { value: airlight }, surface: { value: surface },
      sigma_t: sigmaT, light_colour: { value: new THREE.Vector3(...lightColour) },
      exposure: { value: 1 }, show_scene: { value: 1 },
      through: { value: through }, use_through: { value: through ? 1 : 0 },
    };
    const mesh = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.ShaderMaterial({
      uniforms: this.uniforms,
      vertexShader: 'varying vec2 uv_; void main() { uv_ = uv; gl_Position = vec4(position.xy, 0.0, 1.0); }',
      fragmentShader: `
        uniform sampler2D scene_color; uniform sampler2D airlight; uniform sampler2D surface;
        uniform float sigma_t; uniform float exposure; uniform float show_scene; uniform vec3 light_colour;
        uniform sampler2D through; uniform float use_through;
        varying vec2 uv_;
        void main() {
          float through = use_through > 0.5 ? texture2D(through, uv_).r
                                            : exp(-sigma_t * min(texture2D(surface, uv_).r, 1e30));
          vec3 c = show_scene * through * texture2D(scene_color, uv_).rgb +
                   light_colour * max(texture2D(airlight, uv_).r, 0.0);
          c *= exposure;
          c = c / (1.0 + c);
          gl_FragColor = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
        }`,
      depthTest: false, depthWrite: false,
    }));
    mesh.frustumCulled = false;
    this.scene = new THREE.Scene();
    this.scene.add(mesh);
    this.camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
  }

  // Into the bound render target (the canvas: renderer.setRenderTarget(null) first).
  render(renderer) { renderer.render(this.scene, this.camera); }
}

// Renders the airlight of a light volume for one camera, as `lightvol render --method volume`:
// the scene's distances along the pixel rays (surface pass), the volume with additive float
// blending (RG32F), the resolve (R32F). With `density: true` (a medium of varying density), the
// volume and resolve stages are airlight.glsl's LIGHTVOL_DENSITY ones: the volume pass also sums
// each fragment's signed D(t) from a DensityGrid (web/density.js, setDensityGrid) into a second
// target, which the resolve adds.
// With `resolution` r < 1 the volume and resolve passes run on an image of r·width × r·height
// pixels (rounded up): the surface distances are taken down to it (each low pixel the distance
// of the full pixel under its centre), and an upsampling pass fills the full-size airlight from
// the 2 × 2 low pixels around each pixel, weighted bilinearly and by how close their surface
// distances are to the pixel's own (docs/web.md, "Reduced resolution").
export class AirlightRenderer {
  constructor(renderer, glsl, { width, height, density = false, resolution = 1 }) {
    if (!(resolution > 0 && resolution <= 1))
      throw new Error(`AirlightRenderer: resolution ${resolution}: a scale in (0, 1]`);
    if (density && resolution !== 1)
      throw new Error('AirlightRenderer: a reduced resolution takes homogeneous media only');
    this.resolution = resolution;
    this.reduced = resolution < 1;
    this.density = density;
    this.densityGrid = null;
    this.renderer = renderer;
    this.width = width;
    this.height = height;
    const gl = renderer.getContext();
    this.gl = gl;
    for (const name of ['EXT_color_buffer_float', 'EXT_float_blend'])
      if (!gl.getExtension(name)) throw new Error(`WebGL2 lacks ${name}: no float blending`);
    this.depthClamp = gl.getExtension('EXT_depth_clamp');
    this.table = sunTable();
    this.surfaceTarget = floatTarget(width, height, THREE.RedFormat, true);
    const [lowWidth, lowHeight] = this.lowSize(width, height);
    this.accumulateTarget = floatTarget(lowWidth, lowHeight, THREE.RGFormat, false, density ? 2 : 1);
    this.airlightTarget = floatTarget(width, height, THREE.RedFormat, false);
    if (this.reduced) {
      this.lowSurfaceTarget = floatTarget(lowWidth, lowHeight, THREE.RedFormat, false);
      this.lowAirlightTarget = floatTarget(lowWidth, lowHeight, THREE.RedFormat, false);
    }
    this.common = {
      inv_projection: { value: new THREE.Matrix4() },
      eye_to_world: { value: new THREE.Matrix3() },
      camera_position: { value: new THREE.Vector3() },
      perspective: { value: 1 },
      viewport: { value: new THREE.Vector2(width, height) },
      flip_y: { value: 0 },
      light_type: { value: 0 },
      light_position: { value: new THREE.Vector3() },
      light_direction: { value: new THREE.Vector3() },
      light_near: { value: 0 },
      sigma_s: { value: 0 },
      sigma_t: { value: 0 },
      intensity: { value: 1 },
      phase_type: { value: 0 },
      phase_param: { value: 0 },
      f_table: { value: this.table },
      f_u_max: { value: TABLE.uMax },
      profile_enabled: { value: 0 },
      profile_cos_inner: { value: 1 },
      profile_cos_outer: { value: 1 },
      view_projection: { value: new THREE.Matrix4() },
    };
    const material = (stage, extra, options, withDensity = false) => new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: stageSource(glsl, `LIGHTVOL_${stage}_VERTEX`),
      fragmentShader: stageSource(glsl, `LIGHTVOL_${stage}_FRAGMENT`, withDensity),
      uniforms: { ...this.common, ...extra },
      ...options,
    });
    this.surfaceMaterial = material('SURFACE', { view_projection: { value: new THREE.Matrix4() } },
                                    { side: THREE.DoubleSide });
    // Pass 1's state: no culling, no depth test, additive float blending (light_volume.js draws
    // its live volume with it too).
    this.volumeState = {
      side: THREE.DoubleSide, depthTest: false, depthWrite: false, transparent: true,
      blending: THREE.CustomBlending, blendEquation: THREE.AddEquation,
      blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor,
      blendEquationAlpha: THREE.AddEquation, blendSrcAlpha: THREE.OneFactor,
      blendDstAlpha: THREE.OneFactor,
    };
    // The density grid's uniforms (airlight.glsl's LIGHTVOL_DENSITY, GL_ES branch).
    this.gridUniforms = {
      grid_columns: { value: new THREE.Vector2(1, 1) },
      grid_tile: { value: 1 },
      grid_slices: { value: 2 },
      grid_texture: { value: null },
      grid_reach: { value: null },
    };
    this.volumeMaterial = material('VOLUME', {
      surface: { value: (this.reduced ? this.lowSurfaceTarget : this.surfaceTarget).texture },
      baseline: { value: 1 },
      panels: { value: 2 },
      facing_sign: { value: -1 },
      ...(density ? this.gridUniforms : {}),
    }, this.volumeState, density);
    this.resolveMaterial = material('RESOLVE', {
      accumulated: { value: this.accumulateTarget.textures[0] },
      ...(density ? { accumulated_density: { value: this.accumulateTarget.textures[1] } } : {}),
      baseline: { value: 1 },
    }, { depthTest: false, depthWrite: false }, density);
    // Three vertices, positions unused: the resolve's full-screen triangle comes from gl_VertexID.
    const triangle = new THREE.BufferGeometry();
    triangle.setAttribute('position', new THREE.BufferAttribute(new Float32Array(9), 3));
    this.resolveScene = new THREE.Scene();
    const resolveMesh = new THREE.Mesh(triangle, this.resolveMaterial);
    resolveMesh.frustumCulled = false;
    this.resolveScene.add(resolveMesh);
    this.volumeScene = new THREE.Scene();
    this.surfaceScene = new THREE.Scene();
    this.dummyCamera = new THREE.Camera();
    if (this.reduced) {
      // Full-screen passes of their own: the surface distances taken down, the airlight taken up.
      const pass = (fragmentShader, uniforms) => {
        const scene = new THREE.Scene();
        const mesh = new THREE.Mesh(triangle, new THREE.RawShaderMaterial({
          glslVersion: THREE.GLSL3, vertexShader: stageSource(glsl, 'LIGHTVOL_RESOLVE_VERTEX'),
          fragmentShader: `${PREFIX}${fragmentShader}`, uniforms, depthTest: false, depthWrite: false }));
        mesh.frustumCulled = false;
        scene.add(mesh);
        return scene;
      };
      this.scale = { value: new THREE.Vector2(1, 1) };  // full pixels per low pixel, x and y
      this.downScene = pass(DOWNSAMPLE, { surface: { value: this.surfaceTarget.texture }, scale: this.scale });
      this.upScene = pass(UPSAMPLE, {
        surface: { value: this.surfaceTarget.texture }, low_surface: { value: this.lowSurfaceTarget.texture },
        low_airlight: { value: this.lowAirlightTarget.texture },
        low_counts: { value: this.accumulateTarget.textures[0] }, scale: this.scale });
      this.setScale();
    }
  }

  // The volume and resolve passes' image size for a camera of width × height pixels.
  lowSize(width, height) {
    return [Math.max(1, Math.ceil(width * this.resolution)), Math.max(1, Math.ceil(height * this.resolution))];
  }

  setScale() {
    const [lw, lh] = this.lowSize(this.width, this.height);
    this.scale.value.set(this.width / lw, this.height / lh);
  }

  // A new image size (the camera's, in pixels): the targets keep their textures, reallocated at
  // their next use.
  setSize(width, height) {
    this.width = width;
    this.height = height;
    for (const t of [this.surfaceTarget, this.airlightTarget]) t.setSize(width, height);
    const [lowWidth, lowHeight] = this.lowSize(width, height);
    this.accumulateTarget.setSize(lowWidth, lowHeight);
    if (this.reduced) {
      this.lowSurfaceTarget.setSize(lowWidth, lowHeight);
      this.lowAirlightTarget.setSize(lowWidth, lowHeight);
      this.setScale();
    }
    this.common.viewport.value.set(width, height);
  }

  setVolume(geometry) {
    this.volumeScene.clear();
    const mesh = new THREE.Mesh(geometry, this.volumeMaterial);
    mesh.frustumCulled = false;
    this.volumeScene.add(mesh);
  }

  setScene(geometries) {
    this.surfaceScene.clear();
    for (const g of geometries) {
      const mesh = new THREE.Mesh(g, this.surfaceMaterial);
      mesh.frustumCulled = false;
      this.surfaceScene.add(mesh);
    }
  }

  // light: parseFrame() of the GLB's extras; medium: lightvol's medium JSON.
  setLight(light) {
    const u = this.common;
    u.light_type.value = light.type === 'directional' ? 1 : 0;
    u.light_position.value.copy(light.position);
    u.light_direction.value.copy(light.direction);
    u.light_near.value = light.near;
    this.light = light;
  }

  setMedium(medium) {
    const u = this.common;
    const scattering = medium.scattering ?? 0.05, absorption = medium.absorption ?? 0;
    u.sigma_s.value = scattering;
    u.sigma_t.value = scattering + absorption;
    u.intensity.value = medium.intensity ?? 1;
    const phase = medium.phase ?? { type: 'isotropic' };
    u.phase_type.value = PHASES[phase.type] ?? 0;
    u.phase_param.value = phase.type === 'hg' ? phase.g ?? 0 : phase.type === 'schlick' ? phase.k ?? 0 : 0;
    const profile = medium.profile;
    const useProfile = !!profile && this.light && this.light.type === 'spot';
    u.profile_enabled.value = useProfile ? 1 : 0;
    u.profile_cos_inner.value = useProfile ? Math.cos(profile.inner_deg * Math.PI / 180) : 1;
    u.profile_cos_outer.value = useProfile ? Math.cos(profile.outer_deg * Math.PI / 180) : 1;
    this.volumeMaterial.uniforms.panels.value = useProfile ? 8 : 2;
  }

  // The DensityGrid whose grid the volume pass reads (made each frame in render()).
  setDensityGrid(grid) {
    if (!this.density) throw new Error('AirlightRenderer: constructed without density: true');
    this.densityGrid = grid;
    const g = this.gridUniforms, u = grid.uniforms;
    g.grid_columns.value.copy(u.grid_columns.value);
    g.grid_tile.value = u.grid_tile.value;
    g.grid_slices.value = u.grid_slices.value;
    g.grid_texture.value = u.grid_texture.value;
    g.grid_reach.value = u.grid_reach.value;
  }

  // camera: {view, projection (THREE.Matrix4), flipY}.
  setCamera(camera) {
    this.camera = camera;
    const u = this.common;
    const invView = camera.view.clone().invert();
    u.inv_projection.value.copy(camera.projection).invert();
    u.eye_to_world.value.setFromMatrix4(invView);
    u.camera_position.value.set(0, 0, 0).applyMatrix4(invView);
    u.perspective.value = camera.projection.elements[11] !== 0 ? 1 : 0;
    u.flip_y.value = camera.flipY ? 1 : 0;
    this.surfaceMaterial.uniforms.view_projection.value.multiplyMatrices(camera.projection,
                                                                         camera.view);
    let projection = camera.projection;
    if (!this.depthClamp && u.perspective.value === 1) {
      // No depth clamping: a near plane 1000 times closer and the far plane at infinity, so that
      // no part of the volume in front of the scene is clipped (x, y and w are unchanged).
      projection = camera.projection.clone();
      const e = projection.elements, near = e[14] / (e[10] - 1) * 1e-3;
      e[10] = -1;
      e[14] = -2 * near;
    }
    const vp = new THREE.Matrix4().multiplyMatrices(projection, camera.view);
    u.view_projection.value.copy(vp);
    // A mirroring camera turns counter-clockwise front faces into back faces.
    const e = vp.elements;
    const det3 = e[0] * (e[5] * e[10] - e[9] * e[6]) - e[4] * (e[1] * e[10] - e[9] * e[2]) +
                 e[8] * (e[1] * e[6] - e[5] * e[2]);
    this.volumeMaterial.uniforms.facing_sign.value = det3 < 0 ? 1 : -1;
  }

  // `drawSurfaces` (optional): draws the scene's surfaces into the bound surface target instead of
  // setScene's geometries (the live page's moving objects: light_volume.js).
  render(drawSurfaces = null) {
    const { renderer, gl } = this;
    const previousTarget = renderer.getRenderTarget();
    // The passes clear their targets themselves (the surface to 3e38, "nothing there"): three's
    // own clear would set the surface to the renderer's clear colour, 0, and with no scene every
    // pixel would end at distance 0 with no airlight.
    const autoClear = renderer.autoClear;
    renderer.autoClear = false;
    renderer.setRenderTarget(this.surfaceTarget);
    gl.clearBufferfv(gl.COLOR, 0, new Float32Array([3e38, 0, 0, 0]));
    gl.clearBufferfi(gl.DEPTH_STENCIL, 0, 1, 0);
    if (drawSurfaces) drawSurfaces();
    else renderer.render(this.surfaceScene, this.dummyCamera);
    // A varying density: this frame's opacity map and grid, for this camera and these surfaces.
    if (this.densityGrid)
      this.densityGrid.update({ ...this.camera, width: this.width, height: this.height }, this.readSurface());
    // Reduced resolution: the volume and resolve passes see the low image's pixel rays.
    if (this.reduced) {
      this.common.viewport.value.set(this.accumulateTarget.width, this.accumulateTarget.height);
      renderer.setRenderTarget(this.lowSurfaceTarget);
      renderer.render(this.downScene, this.dummyCamera);
    }

    renderer.setRenderTarget(this.accumulateTarget);
    gl.clearBufferfv(gl.COLOR, 0, new Float32Array([0, 0, 0, 0]));
    if (this.density) gl.clearBufferfv(gl.COLOR, 1, new Float32Array([0, 0, 0, 0]));
    if (this.depthClamp) gl.enable(this.depthClamp.DEPTH_CLAMP_EXT);
    renderer.render(this.volumeScene, this.dummyCamera);
    if (this.depthClamp) gl.disable(this.depthClamp.DEPTH_CLAMP_EXT);

    renderer.setRenderTarget(this.reduced ? this.lowAirlightTarget : this.airlightTarget);
    renderer.render(this.resolveScene, this.dummyCamera);
    if (this.reduced) {
      this.common.viewport.value.set(this.width, this.height);
      renderer.setRenderTarget(this.airlightTarget);
      renderer.render(this.upScene, this.dummyCamera);
    }
    renderer.setRenderTarget(previousTarget);
    renderer.autoClear = autoClear;
  }

  // The airlight, width × height floats, top row first (as lightvol writes images).
  readAirlight() { return this.read(this.airlightTarget); }
  // The surface pass: distance along each pixel's ray to the scene (3e38: nothing), top row first.
  readSurface() { return this.read(this.surfaceTarget); }

  // Per pixel, back faces minus front faces the volume pass counted (pass 1's second channel), top
  // row first: 0 or 1 for a closed volume (1 when the camera is inside), unless the rasterizer
  // dropped or doubled a fragment. With a reduced resolution, of the low image's pixels.
  readFaceCounts() { return this.read(this.accumulateTarget, 1); }

  read(target, channel = 0) {
    const { renderer, gl } = this;
    const { width, height } = target;
    const previousTarget = renderer.getRenderTarget();
    renderer.setRenderTarget(target);
    const rgba = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, rgba);
    renderer.setRenderTarget(previousTarget);
    const out = new Float32Array(width * height);
    const flip = this.common.flip_y.value === 1;
    for (let r = 0; r < height; ++r) {
      const src = flip ? r : height - 1 - r;  // GL row 0 is the bottom (NDC y = -1)
      for (let c = 0; c < width; ++c) out[r * width + c] = rgba[(src * width + c) * 4 + channel];
    }
    return out;
  }
}
