// lightvol's web viewer: index.html?volume=URL&camera=URL&medium=URL[&scene=URL]
// Loads a light volume GLB (static, adaptive, Draco-compressed, omni; its light from the node
// extras lightvol writes), a camera and a medium (lightvol's JSON) and optionally a scene (GLB,
// glTF, PLY or OBJ); renders the airlight with shaders/airlight.glsl into float targets and shows
// it over the lit scene. The first frame is exactly the given camera; then document.title becomes
// 'lightvol:done' and window.lightvolAirlight() returns that frame's airlight (Float32Array,
// width × height, top row first, linear; window.lightvolSurface(): its distances along the pixel
// rays to the scene, 3e38 where none; window.lightvolFaceCounts(): back minus front faces per
// pixel; window.lightvolThrough(), for a medium of varying density: each pixel's transmittance to
// its surface, by which the composite dims the lit scene, 0 where none, else null). The orbit
// camera and the sliders re-render.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { PLYLoader } from 'three/addons/loaders/PLYLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { AirlightRenderer, Composite, parseFrame } from './airlight.js';
import { DensityGrid, loadDensityShaders, parseDensity } from './density.js';

const status = document.getElementById('status');
const say = (text) => { status.textContent = text; };

async function fetchJson(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return response.json();
}
async function fetchText(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return response.text();
}

function gltfLoader() {
  const draco = new DRACOLoader();
  draco.setDecoderPath(new URL('./node_modules/three/examples/jsm/libs/draco/', import.meta.url).href);
  return new GLTFLoader().setDRACOLoader(draco);
}

// Every mesh's geometry of a loaded object, in world space, as plain triangle geometries.
function worldGeometries(root) {
  root.updateMatrixWorld(true);
  const out = [];
  root.traverse((o) => {
    if (!o.isMesh) return;
    const g = o.geometry.clone();
    g.applyMatrix4(o.matrixWorld);
    out.push(g);
  });
  return out;
}

// The lightvol light of a volume GLB: the node extras {"lightvol": {"light": ..., "medium": ...}}.
function lightvolExtras(root) {
  let found = null;
  root.traverse((o) => { if (!found && o.userData && o.userData.lightvol) found = o.userData.lightvol; });
  if (!found) throw new Error('the volume GLB has no lightvol light in its extras (write it with lightvol build)');
  return found;
}

async function loadScene(url) {
  const lower = url.toLowerCase().split('?')[0];
  if (lower.endsWith('.ply')) {
    const g = await new PLYLoader().loadAsync(url);
    return new THREE.Mesh(g);
  }
  if (lower.endsWith('.obj')) return new OBJLoader().loadAsync(url);
  return (await gltfLoader().loadAsync(url)).scene;
}

async function main() {
  const params = new URLSearchParams(location.search);
  const volumeUrl = params.get('volume'), cameraUrl = params.get('camera');
  const mediumUrl = params.get('medium'), sceneUrl = params.get('scene');
  if (!volumeUrl || !cameraUrl) {
    say('usage: index.html?volume=URL&camera=URL&medium=URL[&scene=URL]');
    return;
  }
  say('loading…');
  const shaderUrl = new URL('../shaders/airlight.glsl', import.meta.url).href;
  const [glsl, cameraJson, gltf, sceneRoot] = await Promise.all([
    fetchText(shaderUrl), fetchJson(cameraUrl), gltfLoader().loadAsync(volumeUrl),
    sceneUrl ? loadScene(sceneUrl) : Promise.resolve(null),
  ]);
  const extras = lightvolExtras(gltf.scene);
  let medium = mediumUrl ? await fetchJson(mediumUrl) : extras.medium;
  if (!medium) throw new Error('no medium: give medium=URL (or build the GLB with --medium)');
  medium = structuredClone(medium);
  // A medium of varying density ("density": {"type": "noise", ...}): rendered as `lightvol render
  // --method volume` renders it, with shaders/density.glsl and a per-frame grid (web/density.js).
  const noise = parseDensity(medium, mediumUrl ?? 'the GLB\'s medium');
  const densityShaders = noise ? await loadDensityShaders() : null;

  const camera = parseFrame(cameraJson);
  const width = camera.width, height = camera.height;
  const canvas = document.getElementById('view');
  canvas.width = width;
  canvas.height = height;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.shadowMap.enabled = true;
  THREE.ColorManagement.enabled = false;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  // A shader that does not compile stops the page with its log (three would only log it and draw
  // nothing with it: an image without, say, the density's part, silently).
  let shaderError = null;
  renderer.debug.onShaderError = (gl, program, vertex, fragment) => {
    const log = [vertex, fragment].map((sh) => gl.getShaderInfoLog(sh)).filter((t) => t).join(' ');
    shaderError ??= `a shader did not compile: ${log || gl.getProgramInfoLog(program)}`;
  };

  const airlight = new AirlightRenderer(renderer, glsl, { width, height, density: !!noise });
  const light = parseFrame(extras.light);
  airlight.setLight(light);
  airlight.setMedium(medium);
  if (noise) airlight.setDensityGrid(new DensityGrid(airlight, glsl, densityShaders, extras.light, light, noise));
  const volumeGeometries = worldGeometries(gltf.scene);
  const volumeGeometry = volumeGeometries[0];
  airlight.setVolume(volumeGeometry);
  const triangles = volumeGeometry.index ? volumeGeometry.index.count / 3
                                        : volumeGeometry.attributes.position.count / 3;
  const sceneGeometries = sceneRoot ? worldGeometries(sceneRoot) : [];
  airlight.setScene(sceneGeometries);

  // The lit scene: Lambert surfaces (albedo 0.35) under the GLB's own KHR_lights_punctual light,
  // with shadows, plus a little ambient light; rendered into a float target with lightvol's camera.
  const lit = new THREE.Scene();
  const surfaceMaterial = new THREE.MeshLambertMaterial({
    color: new THREE.Color(0.35, 0.35, 0.35), flatShading: true, side: THREE.DoubleSide });
  for (const g of sceneGeometries) {
    const m = new THREE.Mesh(g, surfaceMaterial);
    m.castShadow = m.receiveShadow = true;
    m.frustumCulled = false;
    lit.add(m);
  }
  let punctual = null;
  gltf.scene.traverse((o) => { if (!punctual && o.isLight) punctual = o; });
  if (punctual) {
    // The light alone (its target is its child), at its world pose: not the node around it, which
    // may be the GLB's root holding the volume mesh too.
    gltf.scene.updateMatrixWorld(true);
    punctual.matrixWorld.decompose(punctual.position, punctual.quaternion, punctual.scale);
    punctual.removeFromParent();
    lit.add(punctual);
    punctual.castShadow = true;
    punctual.shadow.mapSize.set(1024, 1024);
    punctual.shadow.bias = -0.0005;
    punctual.shadow.normalBias = 0.02;
    if (punctual.isSpotLight) punctual.penumbra = 0.2;
    punctual.intensity = medium.intensity ?? 1;  // the medium's I (W/sr), as the airlight's
  }
  lit.add(new THREE.AmbientLight(0xffffff, 0.027));  // about lightvol demo's ambient radiance 0.003
  const litTarget = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType });
  const litCamera = new THREE.PerspectiveCamera();
  litCamera.matrixAutoUpdate = false;
  litCamera.matrixWorldAutoUpdate = false;

  // The volume's wireframe, drawn with the same camera.
  const wire = new THREE.Scene();
  const wireMaterial = new THREE.LineBasicMaterial({ color: 0x66ccff, transparent: true, opacity: 0.35 });
  wire.add(new THREE.LineSegments(new THREE.WireframeGeometry(volumeGeometry), wireMaterial));

  // Composite as lightvol demo's picture (airlight.js's Composite, the live page's too).
  // A varying density dims the lit scene by each pixel's own transmittance (DensityGrid's).
  const composite = new Composite({ scene: litTarget.texture, airlight: airlight.airlightTarget.texture,
                                    surface: airlight.surfaceTarget.texture, sigmaT: airlight.common.sigma_t,
                                    through: noise ? airlight.densityGrid.throughTarget.texture : null });

  // The camera: exactly the JSON's first; the orbit controls then move its view.
  const orbitCamera = new THREE.PerspectiveCamera();
  const invView = camera.view.clone().invert();
  orbitCamera.position.setFromMatrixPosition(invView);
  orbitCamera.up.set(0, 1, 0).transformDirection(invView);
  const box = new THREE.Box3().setFromBufferAttribute(volumeGeometry.attributes.position);
  const centre = box.getCenter(new THREE.Vector3());
  const distance = Math.max(centre.clone().sub(orbitCamera.position).dot(camera.direction), 1e-3);
  const target = orbitCamera.position.clone().addScaledVector(camera.direction, distance);
  orbitCamera.lookAt(target);
  const controls = new OrbitControls(orbitCamera, canvas);
  controls.target.copy(target);
  controls.update();
  let view = camera.view.clone();

  let exposure = null, frame = null;
  const ui = {
    scattering: document.getElementById('scattering'),
    absorption: document.getElementById('absorption'),
    intensity: document.getElementById('intensity'),
    g: document.getElementById('g'),
    wireframe: document.getElementById('wireframe'),
    info: document.getElementById('info'),
  };
  const phase = medium.phase ?? { type: 'isotropic' };
  ui.scattering.value = medium.scattering ?? 0.05;
  ui.absorption.value = medium.absorption ?? 0;
  ui.intensity.value = medium.intensity ?? 1;
  ui.intensity.max = Math.max(Number(ui.intensity.value) * 4, 1);
  ui.g.value = phase.type === 'hg' ? phase.g : 0;
  ui.wireframe.checked = params.get('wireframe') === '1';

  function draw() {
    const t0 = performance.now();
    airlight.setCamera({ view, projection: camera.projection, flipY: camera.flipY });
    airlight.render();
    frame = airlight.readAirlight();  // also waits for the GPU: the frame time includes it
    const ms = performance.now() - t0;
    litCamera.matrixWorldInverse.copy(view);
    litCamera.matrixWorld.copy(view).invert();
    litCamera.projectionMatrix.copy(camera.projection);
    litCamera.projectionMatrixInverse.copy(camera.projection).invert();
    renderer.setRenderTarget(litTarget);
    renderer.setClearColor(0x000000, 1);
    renderer.clear();
    renderer.render(lit, litCamera);
    if (exposure === null) {
      // As lightvol's PNGs: the 99.5th percentile of the picture maps to 4 before x/(1+x).
      const gl = renderer.getContext(), rgba = new Float32Array(width * height * 4);
      gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, rgba);
      const surface = airlight.readSurface(), sigmaT = airlight.common.sigma_t.value;
      const densityThrough = noise ? airlight.read(airlight.densityGrid.throughTarget) : null;
      const picture = new Float32Array(width * height);
      for (let i = 0; i < picture.length; ++i) {
        const row = height - 1 - Math.floor(i / width), col = i % width;  // GL rows bottom-up
        const j = (row * width + col) * 4;
        const through = sceneGeometries.length === 0 ? 0
          : densityThrough ? densityThrough[i] : Math.exp(-sigmaT * Math.min(surface[i], 1e30));
        picture[i] = through * (rgba[j] + rgba[j + 1] + rgba[j + 2]) / 3 + Math.max(frame[i], 0);
      }
      picture.sort();
      const p = picture[Math.min(picture.length - 1, Math.floor(0.995 * picture.length))];
      exposure = p > 0 ? 4 / p : 1;
    }
    renderer.setRenderTarget(null);
    composite.uniforms.exposure.value = exposure;
    composite.uniforms.show_scene.value = sceneGeometries.length > 0 ? 1 : 0;
    renderer.autoClear = true;
    composite.render(renderer);
    if (ui.wireframe.checked) {
      renderer.autoClear = false;
      renderer.render(wire, litCamera);
      renderer.autoClear = true;
    }
    ui.info.textContent = `${triangles.toLocaleString('en')} triangles · airlight ${ms.toFixed(1)} ms · ` +
                          `${width}×${height}` + (airlight.depthClamp ? '' : ' · no depth clamp') +
                          (noise ? ` · noise density, grid ${airlight.densityGrid.options.slices} slices` : '');
  }

  function onMedium() {
    medium.scattering = Number(ui.scattering.value);
    medium.absorption = Number(ui.absorption.value);
    medium.intensity = Number(ui.intensity.value);
    const g = Number(ui.g.value);
    if (g !== 0 || (medium.phase && medium.phase.type === 'hg')) medium.phase = { type: 'hg', g };
    airlight.setMedium(medium);
    if (punctual) punctual.intensity = medium.intensity;
    draw();
  }
  for (const k of ['scattering', 'absorption', 'intensity', 'g']) ui[k].addEventListener('input', onMedium);
  ui.wireframe.addEventListener('change', draw);
  controls.addEventListener('change', () => {
    orbitCamera.updateMatrixWorld();
    view = orbitCamera.matrixWorldInverse.clone();
    draw();
  });

  draw();
  if (shaderError) throw new Error(shaderError);
  const first = frame.slice(), surface = airlight.readSurface(), counts = airlight.readFaceCounts();
  const through = noise ? airlight.read(airlight.densityGrid.throughTarget) : null;
  window.lightvolAirlight = () => first;
  window.lightvolSurface = () => surface;
  window.lightvolFaceCounts = () => counts;
  window.lightvolCurrentAirlight = () => frame;
  window.lightvolThrough = () => through;
  say('');
  document.title = 'lightvol:done';
}

main().catch((e) => {
  say(`error: ${e.message}`);
  console.error(e);
  document.title = 'lightvol:error';
});
