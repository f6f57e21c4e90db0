// lightvol's live page: live.html?scene=URL&light=URL&medium=URL&camera=URL[&animate=1][&size=N]
// [&shadow=0][&adaptive=E[&rounds=N][&count=bound]]. The scene (GLB, glTF, PLY or OBJ) lit by the light of a
// lightvol light JSON (spot, directional or omni: a three.js SpotLight, DirectionalLight or
// PointLight with a size × size shadow map, 512 by default), seen from a lightvol camera JSON, with
// the light's shafts from LightVolume (light_volume.js): the static light volume of that frame's
// shadow map (adaptive=E: build's adaptive quadtree volume at bound E), built on the GPU, and its
// airlight. Drag the light with the gizmo (TransformControls), orbit the camera;
// with animate=1 an object moves through the light. shadow=0 makes the light without castShadow
// (to see the addon's message).
// Hooks (docs/web.md): document.title = 'lightvol:done' after the first frame (the JSON camera's);
// window.lightvolAirlight() (Float32Array, width × height, top row first), lightvolShadowMap()
// (its window depth, top row first; omni: the six faces one under the other), lightvolLight()
// (lightvol's light JSON of that map), lightvolMedium(), lightvolSurface(), lightvolFaceCounts(),
// lightvolIndices(), lightvolPositions() and lightvolFrame() give the frame captured last: the
// first, or the one lightvolStep(n) rendered (it stops the animation, advances it n frames from
// the last captured frame and renders). lightvolTime(n): milliseconds per frame (adaptive=E: also
// the quadtree passes alone, the fix-up rounds the last frame ran and, omni, its seam rounds);
// lightvolTriangles(),
// lightvolConverged(): adaptive=E volumes;
// lightvolResize(w, h): LightVolume.setSize there and back (tests).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { PLYLoader } from 'three/addons/loaders/PLYLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { Composite, parseFrame } from './airlight.js';
import { LightVolume } from './light_volume.js';

const status = document.getElementById('status');
const say = (text, error = false) => {
  status.textContent = text;
  status.style.color = error ? '#f88' : '#aaa';
};

async function fetchJson(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return response.json();
}

async function loadScene(url) {
  const lower = url.toLowerCase().split('?')[0];
  if (lower.endsWith('.ply')) return new THREE.Mesh(await new PLYLoader().loadAsync(url));
  if (lower.endsWith('.obj')) return new OBJLoader().loadAsync(url);
  const draco = new DRACOLoader();
  draco.setDecoderPath(new URL('./node_modules/three/examples/jsm/libs/draco/', import.meta.url).href);
  return (await new GLTFLoader().setDRACOLoader(draco).loadAsync(url)).scene;
}

// A three.js light for a lightvol light JSON (position, direction, up, fov_y_deg/aspect or ortho,
// near, far), with a shadow map of `size` texels across.
function makeLight(json, size, castShadow) {
  if (json.view || json.projection)
    throw new Error('light: live.html places a light by position, direction and up, not by "view"/"projection"');
  const type = json.type ?? 'spot';
  const position = new THREE.Vector3().fromArray(json.position ?? [0, 0, 0]);
  let light, width = size, height = size;
  if (type === 'spot') {
    light = new THREE.SpotLight(0xffffff, 1, 0, THREE.MathUtils.degToRad(json.fov_y_deg / 2), 0.2, 2);
    height = Math.max(2, Math.round(size / (json.aspect ?? 1)));
  } else if (type === 'directional') {
    light = new THREE.DirectionalLight(0xffffff, 1);
    const [l, r, b, t] = json.ortho;
    Object.assign(light.shadow.camera, { left: l, right: r, bottom: b, top: t });
    height = Math.max(2, Math.round(size * (t - b) / (r - l)));
  } else if (type === 'omni') {
    light = new THREE.PointLight(0xffffff, 1, 0, 2);
  } else {
    throw new Error(`light: type "${type}" is not spot, directional or omni`);
  }
  light.position.copy(position);
  if (type !== 'omni') {
    light.target.position.copy(position).add(new THREE.Vector3().fromArray(json.direction));
    light.shadow.camera.up.fromArray(json.up ?? [0, 1, 0]);
  }
  light.shadow.camera.near = json.near;
  light.shadow.camera.far = json.far;
  light.shadow.camera.updateProjectionMatrix();
  light.shadow.mapSize.set(width, height);
  light.shadow.bias = -0.0005;
  light.castShadow = castShadow;
  return light;
}

// As lightvol demo's picture: a warm light (about 3,000 K; the shafts too), a faint cool sky.
const LIGHT_COLOUR = [1.0, 0.72, 0.42];

async function main() {
  const params = new URLSearchParams(location.search);
  const lightUrl = params.get('light'), cameraUrl = params.get('camera');
  const sceneUrl = params.get('scene'), mediumUrl = params.get('medium');
  if (!lightUrl || !cameraUrl) {
    say('usage: live.html?scene=URL&light=URL&medium=URL&camera=URL[&animate=1][&size=N]', true);
    console.error('lightvol live: no light= or camera= in the address');
    document.title = 'lightvol:error';
    return;
  }
  const size = Number(params.get('size') ?? 512);
  if (!(size >= 2 && size <= 4096)) throw new Error(`size=${params.get('size')}: a shadow map size from 2 to 4096`);
  const animate = params.get('animate') === '1';
  // adaptive=E: build's adaptive volume at bound E (--adaptive --max-error E --tessellation
  // quadtree), made on the GPU every frame; rounds=N its fix-up rounds a frame; count=bound its
  // grid draw sized by a bound rather than by the read-back count (live_adaptive.js).
  const maxError = params.has('adaptive') ? Number(params.get('adaptive')) : undefined;
  if (maxError !== undefined && !(Number.isFinite(maxError) && maxError >= 0))
    throw new Error(`adaptive=${params.get('adaptive')}: a bound E >= 0 (world units along the texel rays)`);
  const rounds = params.has('rounds') ? Number(params.get('rounds')) : undefined;
  const count = params.get('count') ?? undefined;
  // resolution=R: LightVolume's airlight on an image R times the camera's on each side, taken up
  // to it by a depth-aware upsampling.
  const resolution = params.has('resolution') ? Number(params.get('resolution')) : 1;
  say('loading…');
  const [glsl, adaptiveGlsl, lightJson, cameraJson, medium, sceneRoot] = await Promise.all([
    LightVolume.loadShader(), maxError !== undefined ? LightVolume.loadAdaptiveShader() : Promise.resolve(null),
    fetchJson(lightUrl), fetchJson(cameraUrl),
    mediumUrl ? fetchJson(mediumUrl) : Promise.resolve({ scattering: 0.05, absorption: 0.01, intensity: 10 }),
    sceneUrl ? loadScene(sceneUrl) : Promise.resolve(null),
  ]);

  const frameOfCamera = parseFrame(cameraJson);
  const width = cameraJson.width ?? 640, height = cameraJson.height ?? 480;
  const canvas = document.getElementById('view');
  canvas.width = width;
  canvas.height = height;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.shadowMap.enabled = true;
  THREE.ColorManagement.enabled = false;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;

  // The scene: Lambert surfaces under the light (intensity: the medium's I), a little ambient light.
  const scene = new THREE.Scene();
  const surfaceMaterial = new THREE.MeshLambertMaterial({ color: new THREE.Color(0.35, 0.35, 0.35),
                                                          side: THREE.DoubleSide });
  const box = new THREE.Box3();
  if (sceneRoot) {
    sceneRoot.traverse((o) => {
      if (!o.isMesh) return;
      o.material = surfaceMaterial;
      o.castShadow = o.receiveShadow = true;
    });
    scene.add(sceneRoot);
    box.setFromObject(sceneRoot);
  }
  const light = makeLight(lightJson, size, params.get('shadow') !== '0');
  light.intensity = medium.intensity ?? 1;
  light.color.setRGB(...LIGHT_COLOUR);
  scene.add(light);
  if (light.target) scene.add(light.target);
  // Lambert radiance albedo/π × 0.002 ≈ 0.0002, lightvol demo's ambient radiance.
  scene.add(new THREE.AmbientLight(new THREE.Color(0.5, 0.62, 0.9), 0.002));

  // The moving object: a ball on a line across the light, between the light and the scene.
  const lightPosition = light.position.clone();
  const centre = box.isEmpty() ? lightPosition.clone().add(new THREE.Vector3(0, -5, 0)) : box.getCenter(new THREE.Vector3());
  const axis = lightJson.type === 'omni' ? centre.clone().sub(lightPosition).normalize()
                                        : new THREE.Vector3().fromArray(lightJson.direction).normalize();
  const reach = Math.max(centre.clone().sub(lightPosition).dot(axis), 4 * lightJson.near);
  const middle = lightPosition.clone().addScaledVector(axis, 0.45 * reach);
  let across = new THREE.Vector3().crossVectors(axis, new THREE.Vector3(0, 1, 0));
  if (across.lengthSq() < 1e-6) across = new THREE.Vector3(1, 0, 0);
  across.normalize();
  const halfField = lightJson.type === 'directional'
      ? 0.5 * (lightJson.ortho[1] - lightJson.ortho[0])
      : 0.45 * reach * Math.tan(THREE.MathUtils.degToRad(lightJson.type === 'spot' ? lightJson.fov_y_deg / 2 : 45));
  const amplitude = 0.6 * halfField;
  const ball = new THREE.Mesh(new THREE.IcosahedronGeometry(0.2 * amplitude, 3), surfaceMaterial);
  ball.castShadow = ball.receiveShadow = true;
  ball.visible = animate;
  scene.add(ball);
  const PERIOD = 120;  // frames
  const place = (frame) => ball.position.copy(middle).addScaledVector(across, amplitude * Math.sin(2 * Math.PI * frame / PERIOD));

  // The camera: exactly the JSON's at first; the orbit controls then move it.
  const camera = new THREE.PerspectiveCamera();
  const invView = frameOfCamera.view.clone().invert();
  camera.position.setFromMatrixPosition(invView);
  camera.up.set(0, 1, 0).transformDirection(invView);
  const distance = Math.max(centre.clone().sub(camera.position).dot(frameOfCamera.direction), 1);
  const target = camera.position.clone().addScaledVector(frameOfCamera.direction, distance);
  camera.lookAt(target);
  camera.projectionMatrix.copy(frameOfCamera.projection);
  camera.projectionMatrixInverse.copy(frameOfCamera.projection).invert();
  const orbit = new OrbitControls(camera, canvas);
  orbit.target.copy(target);
  orbit.update();

  const volume = new LightVolume(renderer, light, { glsl, width, height, medium, maxError, adaptiveGlsl, rounds, count,
                                                      resolution });

  // The lit scene into a float target; the composite as the viewer's (airlight.js's Composite):
  // the scene through the medium plus the airlight in the light's colour, × exposure, x/(1+x), sRGB.
  const litTarget = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType });
  const sigmaT = (medium.scattering ?? 0.05) + (medium.absorption ?? 0);
  const composite = new Composite({ scene: litTarget.texture, airlight: volume.airlightTexture,
                                    surface: volume.surfaceTexture, sigmaT: { value: sigmaT },
                                    lightColour: LIGHT_COLOUR });

  // The light's gizmo, drawn over the picture.
  const gizmo = new TransformControls(camera, canvas);
  gizmo.attach(light);
  const gizmoScene = new THREE.Scene();
  gizmoScene.add(gizmo.getHelper());

  const info = document.getElementById('info');
  let frame = 0, exposure = null;
  function draw() {
    if (animate) place(frame);
    scene.updateMatrixWorld();
    renderer.setRenderTarget(litTarget);
    renderer.setClearColor(0x000000, 1);
    renderer.render(scene, camera);  // the light's shadow map, then the lit scene
    const t0 = performance.now();
    volume.render(scene, camera);
    const ms = performance.now() - t0;
    if (exposure === null) {
      // As lightvol demo's picture: the 99.5th percentile of the first frame maps to 1.2 before
      // x/(1+x).
      const air = volume.readAirlight(), surface = volume.readSurface();
      const gl = renderer.getContext(), rgba = new Float32Array(width * height * 4);
      renderer.setRenderTarget(litTarget);
      gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, rgba);
      const picture = new Float32Array(width * height);
      for (let i = 0; i < picture.length; ++i) {
        const j = ((height - 1 - Math.floor(i / width)) * width + i % width) * 4;  // GL rows bottom-up
        const through = Math.exp(-sigmaT * Math.min(surface[i], 1e30));
        picture[i] = through * (rgba[j] + rgba[j + 1] + rgba[j + 2]) / 3 + Math.max(air[i], 0);
      }
      picture.sort();
      const p = picture[Math.min(picture.length - 1, Math.floor(0.995 * picture.length))];
      exposure = p > 0 ? 1.2 / p : 1;
      composite.uniforms.exposure.value = exposure;
    }
    renderer.setRenderTarget(null);
    composite.render(renderer);
    renderer.autoClear = false;
    renderer.render(gizmoScene, camera);
    renderer.autoClear = true;
    const [w, h] = volume.size;
    info.textContent = `${lightJson.type ?? 'spot'} light · shadow map ${w}×${h}${volume.type === 'omni' ? ' ×6' : ''} · ` +
                       `${volume.adaptive ? `adaptive, E = ${maxError}` : `${volume.triangles.toLocaleString('en')} triangles`} · volume + airlight ${ms.toFixed(1)} ms (CPU side) · ` +
                       `frame ${frame}`;
  }

  let captured = null;
  const capture = () => {
    captured = { frame, airlight: volume.readAirlight(), shadowMap: volume.readShadowMap(),
                 light: structuredClone(volume.lightJson()), medium: structuredClone(volume.lastMediumJson()),
                 surface: volume.readSurface(),
                 counts: volume.readFaceCounts(),
                 indices: volume.adaptive ? null : volume.buildIndices(),
                 positions: volume.adaptive ? null : volume.readPositions(),
                 triangles: volume.adaptive ? volume.readTriangles() : null,
                 converged: volume.adaptive ? volume.converged() : true };
  };
  window.lightvolAirlight = () => captured.airlight;
  window.lightvolShadowMap = () => captured.shadowMap;
  window.lightvolLight = () => captured.light;
  window.lightvolMedium = () => captured.medium;  // the medium the airlight used (spot: the cone's profile)
  window.lightvolSurface = () => captured.surface;
  window.lightvolFaceCounts = () => captured.counts;
  window.lightvolFrame = () => captured.frame;
  window.lightvolIndices = () => captured.indices;  // the volume's triangles (build's)
  window.lightvolPositions = () => captured.positions;  // its vertices, as the GPU made them
  // adaptive=E: the volume's triangles as drawn ([kind, col, row] × 3: LightVolume.readTriangles)
  // and whether the frame's fix-up rounds converged.
  window.lightvolTriangles = () => captured.triangles;
  window.lightvolConverged = () => captured.converged;

  const play = document.getElementById('play');
  play.checked = animate;
  play.disabled = !animate;
  // For the test of LightVolume.setSize: the airlight at another size, then at this one again.
  window.lightvolResize = (w, h) => {
    volume.setSize(w, h);
    volume.render(scene, camera);
    const other = volume.readAirlight();
    volume.setSize(width, height);
    return other.length;
  };
  window.lightvolStep = (n = 1) => {
    play.checked = false;
    frame = captured.frame + n;
    draw();
    capture();
    return frame;
  };
  // Milliseconds per frame over n frames of the current state, each waited for (a 1-pixel read):
  // the whole frame (shadow map, lit scene, live volume and airlight, composite) and the live
  // volume and airlight alone (volume.render after the shadow map is made).
  window.lightvolTime = (n = 10) => {
    play.checked = false;
    const gl = renderer.getContext(), pixel = new Uint8Array(4);
    const wait = () => {  // a read of the canvas waits for every command before it
      renderer.setRenderTarget(null);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    };
    draw();
    wait();
    let t0 = performance.now();
    for (let i = 0; i < n; ++i) { draw(); wait(); }
    const frameMs = (performance.now() - t0) / n;
    let volumeMs = 0;
    for (let i = 0; i < n; ++i) {
      renderer.setRenderTarget(litTarget);
      renderer.render(scene, camera);
      wait();
      t0 = performance.now();
      volume.render(scene, camera);
      wait();
      volumeMs += performance.now() - t0;
    }
    // Adaptive volumes: the quadtree's passes alone (the frame's map and light again).
    let passesMs = null;
    if (volume.adaptive) {
      passesMs = 0;
      for (let i = 0; i < n; ++i) {
        t0 = performance.now();
        volume.adaptive.generate(volume.lightJson(), volume.depthTextures(), ...volume.size);
        wait();
        passesMs += performance.now() - t0;
      }
      passesMs /= n;
    }
    return { frame: frameMs, volume: volumeMs / n, passes: passesMs, rounds: volume.adaptive ? volume.adaptive.roundsRun : null,
             seamRounds: volume.adaptive && volume.adaptive.omni ? volume.adaptive.seamRoundsRun : null,
             triangles: volume.adaptive ? volume.readTriangles().length : volume.triangles, size: volume.size };
  };
  gizmo.addEventListener('dragging-changed', (e) => { orbit.enabled = !e.value; });
  gizmo.addEventListener('change', () => { if (!play.checked) draw(); });
  orbit.addEventListener('change', () => { if (!play.checked) draw(); });

  draw();
  capture();
  say('');
  document.title = 'lightvol:done';
  const loop = () => {
    if (play.checked) {
      ++frame;
      draw();
    }
    requestAnimationFrame(loop);
  };
  requestAnimationFrame(loop);
}

main().catch((e) => {
  say(`error: ${e.message}`, true);
  document.getElementById('view').style.display = 'none';  // no black picture under the message
  console.error(`lightvol live: ${e.message}`);
  document.title = 'lightvol:error';
});
