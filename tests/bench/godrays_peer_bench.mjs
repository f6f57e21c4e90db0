// lightvol's live volume (web/light_volume.js on web/live.html) against the three.js peer the issue
// names, three-good-godrays 0.11.2 (ray marching of the light's shadow map, a bilateral blur, a
// depth-aware upsampling), in one headless chromium (SwiftShader) in one run: the same scene,
// camera and light (`lightvol demo`'s scene and camera; a directional light and a point light, the
// peer has no spot lights), each against lightvol's CPU reference (`lightvol render --method
// reference` of `lightvol build`'s volume of the very shadow map the page used), and their frame
// times. One table.
//   node tests/bench/godrays_peer_bench.mjs PATH/TO/lightvol [--frames N] [--demo-size N]
//        [--map N] [--omni-map N] [--live LIST] [--live-only]
// --live: the live page's settings, one row each, separated by commas, each a query string added
// to live.html's address ("static" for none; default "static,resolution=0.5,adaptive=0.05"; the
// error column is against the reference of build's static volume of the page's map, adaptive
// rows too). --live-only: no peer.
// KEEP=1 keeps the work folder (maps, volumes, references and the peer's images as PFM).
// The peer and its peers (three 0.182.0, postprocessing 6.39.6) are installed with npm into a
// scratch folder outside the repository (PEER_DIR, default /tmp/lightvol-peer), where its page is
// generated too; nothing of it enters the source tree.
//
// The mapping of the media (docs/performance.md says why):
// - lightvol: a thin medium, σs = 1e-5 /m, σa = 0, isotropic phase, I = 4π·1e5, so σs·I·p = 1 and
//   the airlight is ∫ V(t) e^(−σt(s+t)) dt (directional, metres of lit path; e^(−σt·…) ≥ 0.9994
//   here) or ∫ V e^(…) / d² dt (point light).
// - the peer: illum = (ρ·L/N) Σ V(x_i) (1 − d_i/far)^a (its shader), shown as f = 1 − e^(−illum)
//   mixed over the scene colour: drawn over a black scene with colour white, f is what the page
//   reads back (the output pass's 8-bit dithering removed), illum = −ln(1 − f). Directional: a = 0
//   and the peer's airlight is illum / ρ (ρ = its default 1/128), exactly lightvol's quantity.
//   Point: no a gives 1/d², so the peer's airlight is k·illum with k fitted by least squares to the
//   reference (its best case); the table says so.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, symlinkSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const args = process.argv.slice(2);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : fallback;
};
const lightvol = args[0] && resolve(args[0]);
if (!lightvol || !existsSync(lightvol)) {
  console.error('usage: godrays_peer_bench.mjs PATH/TO/lightvol [--frames N] [--demo-size N] [--map N] [--omni-map N]');
  process.exit(2);
}
const frames = Number(option('--frames', 3));
const demoSize = Number(option('--demo-size', 256));  // the camera: demoSize × 15/16 wide
const mapSize = Number(option('--map', 512));         // the directional light's map
const omniSize = Number(option('--omni-map', 256));   // each cube face of the point light's map
const TOLERANCE = 0.01;
const liveSettings = option('--live', 'static,resolution=0.5,adaptive=0.05').split(',');
const liveOnly = args.includes('--live-only');

const web = fileURLToPath(new URL('../../web', import.meta.url));
const repository = resolve(web, '..');
const { serve } = await import(pathToFileURL(join(web, 'serve.mjs')).href);
const { DEMO_LIGHTS, launchChromium, readExr, relativeL2, writePfm } =
  await import(pathToFileURL(join(web, 'tests', 'support.mjs')).href);

// ---- the peer, in its scratch folder, with its own page --------------------------------------------
const PEER = { 'three': '0.182.0', 'postprocessing': '6.39.6', 'three-good-godrays': '0.11.2' };
const scratch = resolve(process.env.PEER_DIR ?? join(tmpdir(), 'lightvol-peer'));
mkdirSync(scratch, { recursive: true });
const installed = (name) => {
  try {
    return JSON.parse(readFileSync(join(scratch, 'node_modules', name, 'package.json'), 'utf8')).version;
  } catch {
    return null;
  }
};
if (Object.entries(PEER).some(([name, version]) => installed(name) !== version)) {
  execFileSync('npm', ['install', '--prefix', scratch, '--no-audit', '--no-fund', '--no-save', '--loglevel=error',
                       ...Object.entries(PEER).map(([n, v]) => `${n}@${v}`)], { stdio: ['ignore', 'ignore', 'inherit'] });
}
// The peer's page imports the addon (for the shadow map, light and surfaces that lightvol's
// reference needs, read once, never timed) from the repository through links.
for (const name of ['web', 'shaders'])
  if (!existsSync(join(scratch, name))) symlinkSync(join(repository, name), join(scratch, name));
writeFileSync(join(scratch, 'godrays.html'), `<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>three-good-godrays</title><link rel="icon" href="data:,">
<script type="importmap">
{ "imports": {
    "three": "./node_modules/three/build/three.module.js",
    "three/addons/": "./node_modules/three/examples/jsm/",
    "postprocessing": "./node_modules/postprocessing/build/index.js",
    "three-good-godrays": "./node_modules/three-good-godrays/build/three-good-godrays.esm.js" } }
</script></head>
<body style="margin:0;background:#000"><canvas id="view"></canvas>
<script type="module" src="./godrays.js"></script></body></html>
`);
writeFileSync(join(scratch, 'godrays.js'), `// Generated by lightvol's tests/bench/godrays_peer_bench.mjs.
// godrays.html?scene=URL&light=URL&camera=URL&medium=URL&size=N: the scene of live.html (black,
// so that the output is the peer's in-scattering alone), its directional or point light and camera.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { EffectComposer, RenderPass } from 'postprocessing';
import { GodraysPass } from 'three-good-godrays';
import { parseFrame } from './web/airlight.js';
import { LightVolume } from './web/light_volume.js';

const fetchJson = async (u) => { const r = await fetch(u); if (!r.ok) throw new Error(u + ': HTTP ' + r.status); return r.json(); };
async function main() {
  const p = new URLSearchParams(location.search);
  const [lightJson, cameraJson, medium, gltf, glsl] = await Promise.all([
    fetchJson(p.get('light')), fetchJson(p.get('camera')), fetchJson(p.get('medium')),
    new GLTFLoader().loadAsync(p.get('scene')), LightVolume.loadShader()]);
  const size = Number(p.get('size'));
  const width = cameraJson.width, height = cameraJson.height;
  const canvas = document.getElementById('view');
  canvas.width = width; canvas.height = height;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.BasicShadowMap;  // the peer's README: no depth copy each frame
  THREE.ColorManagement.enabled = false;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  const scene = new THREE.Scene();
  const black = new THREE.MeshBasicMaterial({ color: 0x000000, side: THREE.DoubleSide });
  gltf.scene.traverse((o) => { if (o.isMesh) { o.material = black; o.castShadow = o.receiveShadow = true; } });
  scene.add(gltf.scene);
  // The light as live.html makes it (web/live.js makeLight).
  let light;
  const position = new THREE.Vector3().fromArray(lightJson.position);
  if (lightJson.type === 'directional') {
    light = new THREE.DirectionalLight(0xffffff, 1);
    const [l, r, b, t] = lightJson.ortho;
    Object.assign(light.shadow.camera, { left: l, right: r, bottom: b, top: t });
    light.shadow.mapSize.set(size, Math.max(2, Math.round(size * (t - b) / (r - l))));
    light.target.position.copy(position).add(new THREE.Vector3().fromArray(lightJson.direction));
    light.shadow.camera.up.fromArray(lightJson.up ?? [0, 1, 0]);
  } else {
    light = new THREE.PointLight(0xffffff, 1, 0, 2);
    light.shadow.mapSize.set(size, size);
  }
  light.position.copy(position);
  light.shadow.camera.near = lightJson.near;
  light.shadow.camera.far = lightJson.far;
  light.shadow.camera.updateProjectionMatrix();
  light.shadow.bias = -0.0005;
  light.castShadow = true;
  scene.add(light);
  if (light.target) scene.add(light.target);
  // The camera as live.html's (its projection is the JSON's; near and far for the peer's depths).
  const frame = parseFrame(cameraJson);
  const camera = new THREE.PerspectiveCamera();
  const invView = frame.view.clone().invert();
  camera.position.setFromMatrixPosition(invView);
  camera.up.set(0, 1, 0).transformDirection(invView);
  camera.lookAt(camera.position.clone().add(frame.direction));
  camera.projectionMatrix.copy(frame.projection);
  camera.projectionMatrixInverse.copy(frame.projection).invert();
  camera.near = cameraJson.near; camera.far = cameraJson.far;
  scene.updateMatrixWorld();
  camera.updateMatrixWorld();

  const composer = new EffectComposer(renderer, { frameBufferType: THREE.HalfFloatType });
  const renderPass = new RenderPass(scene, camera);
  composer.addPass(renderPass);
  const godrays = new GodraysPass(light, camera, {});
  godrays.renderToScreen = true;
  composer.addPass(godrays);
  // Its output pass dithers for 8-bit screens (±0.5/255): off, to read its value.
  const out = godrays.compositorPass.fullscreenMaterial;
  out.fragmentShader = out.fragmentShader.replace('#define DITHERING', '');
  out.needsUpdate = true;
  const settings = (s) => ({ color: new THREE.Color(1, 1, 1), gammaCorrection: false, ...s });

  // lightvol's view of the same frame: the map the peer marches, its light JSON, the surfaces.
  renderer.render(scene, camera);
  const volume = new LightVolume(renderer, light, { glsl, width, height, medium });
  volume.render(scene, camera);
  const captured = { map: volume.readShadowMap(), light: volume.lightJson(), medium: volume.lastMediumJson(),
                     surface: volume.readSurface(), airlight: volume.readAirlight(), size: volume.size };
  window.peerCapture = () => ({ ...captured, map: Array.from(captured.map), surface: Array.from(captured.surface),
                                airlight: Array.from(captured.airlight) });
  const gl = renderer.getContext();
  const target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType });
  // The composer's first pass as composer.render() runs it: the scene, then its depth copied where
  // the peer reads it.
  const scenePass = () => {
    renderPass.render(renderer, composer.inputBuffer, composer.outputBuffer);
    if (renderPass.needsDepthBlit && composer.depthRenderTarget !== null) composer.blitDepthBuffer(composer.inputBuffer);
  };
  // One frame at settings s: the peer's output over the black scene, R, top row first.
  window.peerRender = (s) => {
    godrays.setParams(settings(s));
    scenePass();
    godrays.renderToScreen = false;
    godrays.render(renderer, composer.inputBuffer, target);
    godrays.renderToScreen = true;
    renderer.setRenderTarget(target);
    const rgba = new Float32Array(4 * width * height);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, rgba);
    const f = new Array(width * height);
    for (let r = 0; r < height; ++r)
      for (let c = 0; c < width; ++c) f[r * width + c] = rgba[4 * ((height - 1 - r) * width + c)];
    return f;
  };
  // Milliseconds per frame over n frames, each waited for: the whole frame (the shadow map, the
  // scene, the god rays, composited to the canvas: composer.render) and the god-rays pass alone.
  window.peerTime = (s, n) => {
    godrays.setParams(settings(s));
    const pixel = new Uint8Array(4);
    const wait = () => { renderer.setRenderTarget(null); gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); };
    composer.render(); wait();
    let t0 = performance.now();
    for (let i = 0; i < n; ++i) { composer.render(); wait(); }
    const whole = (performance.now() - t0) / n;
    let part = 0;
    for (let i = 0; i < n; ++i) {
      scenePass(); wait();
      t0 = performance.now();
      godrays.render(renderer, composer.inputBuffer, composer.outputBuffer); wait();
      part += performance.now() - t0;
    }
    return { frame: whole, part: part / n };
  };
  // A first frame: the pass binds the shadow map and makes its blur pass in its first render.
  window.peerRender({});
  window.peerObjects = { renderer, scene, camera, light, composer, renderPass, godrays, target };
  document.title = 'peer:done';
}
main().catch((e) => { console.error('peer page: ' + e.message); document.title = 'peer:error ' + e.message; });
`);

// ---- lightvol's inputs: the demo's scene and camera, a directional and a point light -------------
const work = mkdtempSync(join(tmpdir(), 'lightvol-peer-bench-'));
const run = (...a) => execFileSync(lightvol, [...a, '--quiet'], { cwd: work, stdio: ['ignore', 'ignore', 'inherit'] });
run('demo', '--out', '.', '--size', String(demoSize));
const camera = JSON.parse(readFileSync(join(work, 'camera.json'), 'utf8'));
writeFileSync(join(work, 'camera_radial.json'), JSON.stringify({ ...camera, depth: 'radial' }));
const LIGHTS = { directional: DEMO_LIGHTS.directional, point: DEMO_LIGHTS.omni };
for (const [name, json] of Object.entries(LIGHTS)) writeFileSync(join(work, `light_${name}.json`), JSON.stringify(json));
const SIGMA_S = 1e-5;
const thin = { scattering: SIGMA_S, absorption: 0, intensity: 4 * Math.PI / SIGMA_S, phase: { type: 'isotropic' } };
writeFileSync(join(work, 'thin.json'), JSON.stringify(thin));
const DENSITY = 1 / 128;  // the peer's default ρ

// lightvol's reference of a frame: build's volume of its map, the exact sum with its surfaces.
function reference(tag, c) {
  const faces = c.light.type === 'omni' ? 6 : 1;
  const [w, h] = c.size;
  writePfm(join(work, `${tag}_map.pfm`), c.map, w, h * faces);
  writeFileSync(join(work, `${tag}_light.json`), JSON.stringify(c.light));
  writePfm(join(work, `${tag}_surface.pfm`), c.surface.map((t) => (t >= 1e38 ? 1e30 : t)), camera.width, camera.height);
  run('build', `${tag}_map.pfm`, '--light', `${tag}_light.json`, '--out', `${tag}_volume.off`);
  run('render', `${tag}_volume.off`, '--light', `${tag}_light.json`, '--camera', 'camera_radial.json',
      '--depth', `${tag}_surface.pfm`, '--medium', 'thin.json', '--method', 'reference', '--out', `${tag}_reference.exr`);
  const { values } = readExr(join(work, `${tag}_reference.exr`));
  if (process.env.KEEP) writePfm(join(work, `${tag}_reference.pfm`), values, camera.width, camera.height);
  return values;
}

const { server, url } = await serve({ data: work });
const peerServer = await serve({ root: scratch, data: work });
const profile = mkdtempSync(join(tmpdir(), 'lightvol-chromium-'));
const browser = await launchChromium(profile);
const open = async (address, done) => {
  const page = await browser.newPage();
  const messages = [];
  page.on('console', (m) => messages.push(m.text()));
  page.on('pageerror', (e) => messages.push(e.message));
  await page.goto(address);
  await page.waitForFunction(() => /^(lightvol|peer):/.test(document.title), { timeout: 900000 });
  const title = await page.title();
  if (title !== done) throw new Error(`${address}: ${title}: ${messages.join(' | ')}`);
  return page;
};

const grid = [];  // the peer's step count, blur and resolution scale, cheapest first
for (const scale of [0.5, 1]) for (const steps of [60, 120, 240, 480, 960]) for (const blur of [true, false])
  grid.push({ raymarchSteps: steps, blur, resolutionScale: scale });
grid.sort((a, b) => a.raymarchSteps * a.resolutionScale ** 2 - b.raymarchSteps * b.resolutionScale ** 2);
const describe = (s) => `${s.raymarchSteps} steps, blur ${s.blur ? 'on' : 'off'}, scale ${s.resolutionScale}`;
const rows = [], notes = [];
const seconds = (ms) => `${(ms / 1000).toFixed(2)} s`;
try {
  console.log(`camera ${camera.width}x${camera.height}; directional map ${mapSize}², point light 6 × ${omniSize}²; ` +
              `${frames} frames a time; peer ${Object.entries(PEER).map(([n, v]) => `${n} ${v}`).join(', ')} in ${scratch}`);
  for (const [name, json] of Object.entries(LIGHTS)) {
    const size = name === 'point' ? omniSize : mapSize;
    const query = `scene=/data/scene.glb&light=/data/light_${name}.json&medium=/data/thin.json&camera=/data/camera.json&size=${size}`;
    // lightvol's live page at each setting: its airlight against the reference of its own map
    // (build's static volume of it), and its times.
    for (const setting of liveSettings) {
      const extra = setting === 'static' ? '' : `&${setting}`;
      const live = await open(url(`/web/live.html?${query}${extra}`), 'lightvol:done');
      const lc = await live.evaluate(() => ({
        map: Array.from(window.lightvolShadowMap()), light: window.lightvolLight(), surface: Array.from(window.lightvolSurface()),
        airlight: Array.from(window.lightvolAirlight()) }));
      const faces = lc.light.type === 'omni' ? 6 : 1;
      const mw = faces === 6 ? Math.round(Math.sqrt(lc.map.length / 6)) : size;
      lc.size = [mw, lc.map.length / mw / faces];
      const tag = `${name}_live_${setting.replace(/[^a-z0-9.]+/g, '_')}`;
      const liveReference = reference(tag, lc);
      if (process.env.KEEP) writePfm(join(work, `${tag}_airlight.pfm`), lc.airlight, camera.width, camera.height);
      const liveError = relativeL2(lc.airlight, liveReference);
      const lt = await live.evaluate((n) => window.lightvolTime(n), frames);
      await live.close();
      const p = new URLSearchParams(extra);
      const kind = p.has('adaptive') ? `adaptive volume, E = ${p.get('adaptive')}` : 'static volume';
      const scale = p.has('resolution') ? `, airlight at ${p.get('resolution')} resolution` : '';
      rows.push([name, `lightvol LightVolume (live.html), ${kind}${scale}, ${lt.triangles.toLocaleString('en')} triangles`,
                 liveError, lt.frame, lt.volume]);
      console.log(`${name}: live.html ${setting}: ${(100 * liveError).toFixed(3)} %, frame ${seconds(lt.frame)}, ` +
                  `volume ${seconds(lt.volume)}${lt.passes ? `, quadtree passes ${seconds(lt.passes)}` : ''}`);
    }
    if (liveOnly) continue;
    // The peer's page: its map as lightvol reads it, the reference of that map; its settings.
    const peer = await open(peerServer.url(`/godrays.html?${query}`), 'peer:done');
    const pc = await peer.evaluate(() => window.peerCapture());
    const peerReference = reference(`${name}_peer`, pc);
    notes.push(`${name}: LightVolume on the peer's page (three 0.182, the same map) is ` +
               `${(100 * relativeL2(pc.airlight, peerReference)).toFixed(3)} % from the reference of that map`);
    const attenuation = name === 'point' ? 2 : 0;  // directional: no fall-off (lightvol has none)
    // The peer's airlight at settings s: illum = −ln(1 − f), × 1/ρ (directional) or × the
    // least-squares k (point); and the k that would fit best (directional: to check the mapping).
    const evaluate = async (s, a = attenuation) => {
      const f = await peer.evaluate((x) => window.peerRender(x), { ...s, distanceAttenuation: a });
      const illum = f.map((v) => -Math.log(Math.max(1 - v, 1e-7)));
      const clamped = f.filter((v) => v >= 0.4995).length;  // at its maxDensity 0.5
      let num = 0, den = 0;
      for (let i = 0; i < illum.length; ++i) { num += illum[i] * peerReference[i]; den += illum[i] ** 2; }
      const fitted = num / den, k = name === 'point' ? fitted : 1 / DENSITY;
      const airlight = illum.map((v) => k * v);
      if (process.env.KEEP) writePfm(join(work, `${name}_peer_${s.raymarchSteps}_${s.blur}_${s.resolutionScale}_${a}.pfm`),
                                     airlight, camera.width, camera.height);
      // Without the hot spot at a point light in view (its 1/d², which no a gives): the pixels under
      // the reference's 99th percentile, k fitted there.
      const cut = Float64Array.from(peerReference).sort()[Math.floor(0.99 * peerReference.length)];
      const keep = (x) => x.filter((_, i) => peerReference[i] < cut);
      const [ri, rr] = [keep(illum), keep(Array.from(peerReference))];
      let n2 = 0, d2 = 0;
      for (let i = 0; i < ri.length; ++i) { n2 += ri[i] * rr[i]; d2 += ri[i] ** 2; }
      const below = relativeL2(ri.map((v) => (name === 'point' ? n2 / d2 : k) * v), rr);
      return { error: relativeL2(airlight, peerReference), k, fitted, clamped, below };
    };
    const defaults = { raymarchSteps: 60, blur: true, resolutionScale: 0.5 };
    const d = await evaluate(defaults);
    let reached = null, best = { ...d, settings: defaults };
    const tried = [];
    for (const s of grid) {
      const e = await evaluate(s);
      tried.push(`${describe(s)}: ${(100 * e.error).toFixed(2)} %`);
      if (e.error < best.error) best = { ...e, settings: s };
      if (e.error <= TOLERANCE) { reached = { ...e, settings: s }; break; }
    }
    notes.push(`${name}: the peer's search (cheapest first): ${tried.join('; ')}`);
    if (name === 'directional')
      notes.push(`${name}: the peer's scale by the mapping 1/ρ = ${(1 / DENSITY).toFixed(1)}; fitted to the reference ` +
                 `at its defaults ${d.fitted.toFixed(1)}; pixels at its maxDensity clamp: ${d.clamped}`);
    else
      notes.push(`${name}: the peer's scale fitted by least squares: k = ${d.k.toExponential(3)} (defaults); ` +
                 `pixels at its maxDensity clamp: ${d.clamped}`);
    if (name === 'point') {
      // How far the peer's fall-off (1 − d/far)^a is from 1/d², at its best settings found.
      const floor = [];
      for (const a of [0, 1, 2, 4, 8]) floor.push(`a = ${a}: ${(100 * (await evaluate(best.settings, a)).error).toFixed(1)} %`);
      notes.push(`point: the peer at ${describe(best.settings)} by its distanceAttenuation a (k fitted each): ${floor.join(', ')}`);
      notes.push(`point: over the pixels under the reference's 99th percentile (k fitted there): the peer's defaults ` +
                 `${(100 * d.below).toFixed(1)} %, its best found ${(100 * best.below).toFixed(1)} %`);
    }
    const dt = await peer.evaluate((s, n) => window.peerTime(s, n), { ...defaults, distanceAttenuation: attenuation }, frames);
    rows.push([name, `three-good-godrays, its defaults (${describe(defaults)})`, d.error, dt.frame, dt.part]);
    const chosen = reached ?? best;
    const ct = await peer.evaluate((s, n) => window.peerTime(s, n), { ...chosen.settings, distanceAttenuation: attenuation }, frames);
    rows.push([name, `three-good-godrays, ${reached ? 'cheapest reaching 1 %' : 'best found (none reaches 1 %)'}: ` +
               describe(chosen.settings), chosen.error, ct.frame, ct.part]);
    await peer.close();
  }
  console.log('\n| light | method, settings | relative L2 vs reference | whole frame | volumetric part alone |\n|---|---|---|---|---|');
  for (const [light, method, error, frame, part] of rows)
    console.log(`| ${light} | ${method} | ${(100 * error).toFixed(error < 0.001 ? 3 : 2)} % | ${seconds(frame)} | ${seconds(part)} |`);
  console.log('');
  for (const n of notes) console.log(n);
} finally {
  await browser.close();
  server.close();
  peerServer.server.close();
  rmSync(profile, { recursive: true, force: true });
  if (!process.env.KEEP) rmSync(work, { recursive: true, force: true });
  else console.log(`kept ${work}`);
}
