// The web viewer in a real browser: Debian's chromium, headless, WebGL2 on SwiftShader, driven by
// puppeteer-core. On `lightvol demo`'s outputs (static and adaptive volumes, scene, camera, medium),
// a Draco-compressed volume and an omni volume of the bundled scene, the viewer's airlight (window.lightvolAirlight()) must match `lightvol render --method volume` of the
// same camera within 1 % relative L2; without `scene=` (no surface: the airlight runs through the
// whole volume) it must match `render` with a camera depth of 1 everywhere. With a noise medium
// ("density": {"type": "noise"}; spot and omni volumes) likewise, and the homogeneous medium's
// render must be at least 5 % away (the density matters), and the transmittance by which the
// composite dims the surfaces (window.lightvolThrough()) must match `render --composite`'s within
// 1 %; a density lightvol refuses (octaves 13)
// gives lightvol:error and the message naming the key on the page and in the console.
//   node web/tests/browser_test.mjs PATH/TO/lightvol [--demo-size N] [--only CASE] [--screenshot FILE.png]
//                                   [--keep DIR]
// Exit 0 when every case passes, 1 when one fails, 2 when something could not run.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync, mkdirSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import * as THREE from 'three';
import { serve, REPOSITORY } from '../serve.mjs';
import { parseFrame } from '../airlight.js';
import { launchChromium, readExr, relativeL2 } from './support.mjs';

const args = process.argv.slice(2);
const lightvol = args[0] && resolve(args[0]);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : fallback;
};
if (!lightvol || !existsSync(lightvol)) {
  console.error('usage: browser_test.mjs PATH/TO/lightvol [--demo-size N] [--only CASE] [--screenshot FILE.png] [--keep DIR]');
  process.exit(2);
}
const demoSize = Number(option('--demo-size', 128));  // the demo's camera: 480x360 x size/512
const screenshot = option('--screenshot', null);
const keep = option('--keep', null);
const TOLERANCE = 0.01;

const work = keep ? resolve(keep) : mkdtempSync(join(tmpdir(), 'lightvol-web-'));
mkdirSync(work, { recursive: true });
const data = join(REPOSITORY, 'data');
const run = (...a) => execFileSync(lightvol, [...a, '--quiet'], { cwd: work, stdio: ['ignore', 'ignore', 'inherit'] });



// lightvol's camera depth (window depth, the camera's "depth" encoding here) as distances along
// the pixel rays, as surface_distances() computes them; Infinity where nothing was hit.
function surfaceDistances(depth, cameraJson) {
  const { width: w, height: h } = cameraJson;
  const frame = parseFrame(cameraJson);
  const inverse = frame.projection.clone().invert();
  const out = new Float64Array(w * h);
  for (let r = 0; r < h; ++r)
    for (let c = 0; c < w; ++c) {
      const d = depth[r * w + c];
      if (d >= 1) { out[r * w + c] = Infinity; continue; }
      const p = new THREE.Vector4(2 * (c + 0.5) / w - 1, 1 - 2 * (r + 0.5) / h, 2 * d - 1, 1)
          .applyMatrix4(inverse);
      out[r * w + c] = Math.hypot(p.x / p.w, p.y / p.w, p.z / p.w);
    }
  return out;
}

// ---- inputs: `lightvol demo`'s outputs (volumes, scene, camera, medium), an omni volume ----------
run('demo', '--out', '.', '--size', String(demoSize));
const camera = JSON.parse(readFileSync(join(work, 'camera.json'), 'utf8'));
// The demo's own light: its shadow map and volumes are made with it.
const spot = join(data, 'sponza_demo_spot.json');
writeFileSync(join(work, 'omni.json'),
              JSON.stringify({ type: 'omni', position: [0.5, 3.0, -1.0], near: 0.1, far: 40.0 }));
run('shadowmap', join(data, 'sponza_crop.ply'), '--light', 'omni.json', '--size', '48', '--out', 'omni_{face}.exr');
run('build', 'shadow_map.exr', '--light', spot, '--out', 'volume_draco.glb', '--draco');
run('build', 'omni_{face}.exr', '--light', 'omni.json', '--out', 'volume_omni.glb');
// three's EXRLoader reads RGB(A) or Y channels only: the depth's Z channel as RGB, by oiiotool.
execFileSync('oiiotool', ['camera_depth.exr', '--ch', 'R=Z,G=Z,B=Z', '-o', 'camera_depth_rgb.exr'], { cwd: work });
const lightvolSurface = surfaceDistances(readExr(join(work, 'camera_depth_rgb.exr')).values, camera);
// No scene: window depth 1 at every pixel, nothing hit.
execFileSync('oiiotool', ['--pattern', 'constant:color=1', `${camera.width}x${camera.height}`, '1',
                          '--chnames', 'Z', '-d', 'float', '-o', 'empty_depth.exr'], { cwd: work });
const noSurface = new Float64Array(camera.width * camera.height).fill(Infinity);
// A noise medium (docs/design.md §6): the demo's medium with a varying density whose features (a
// wavelength of 1/0.6 units at the first octave, 1/2.4 at the third) are well inside the view.
const medium = JSON.parse(readFileSync(join(work, 'medium.json'), 'utf8'));
writeFileSync(join(work, 'medium_noise.json'), JSON.stringify({
  ...medium, density: { type: 'noise', seed: 7, frequency: 0.6, octaves: 3, lacunarity: 2, gain: 0.5,
                        offset: 1, scale: 0.9 } }));
const only = option('--only', null);
const allCases = [
  { name: 'static', volume: 'volume_static.glb', light: spot },
  { name: 'adaptive', volume: 'volume_adaptive.glb', light: spot },
  { name: 'draco', volume: 'volume_draco.glb', light: spot },
  { name: 'omni', volume: 'volume_omni.glb', light: join(work, 'omni.json') },
  { name: 'no-scene', volume: 'volume_static.glb', light: spot, noScene: true },
  { name: 'noise', volume: 'volume_static.glb', light: spot, medium: 'medium_noise.json' },
  { name: 'noise-omni', volume: 'volume_omni.glb', light: join(work, 'omni.json'), medium: 'medium_noise.json' },
  { name: 'noise-bad', volume: 'volume_static.glb', light: spot, medium: 'medium_noise_bad.json',
    error: /medium_noise_bad\.json: density\.octaves: must be an integer in \[1, 12\], got 13/ },
];
writeFileSync(join(work, 'medium_noise_bad.json'), JSON.stringify({
  ...medium, density: { type: 'noise', octaves: 13 } }));
const cases = allCases.filter((c) => !only || c.name === only);
for (const c of cases.filter((c) => !c.error)) {
  // A noise case must test the density: its reference differs from the homogeneous medium's.
  if (c.medium)
    run('render', c.volume, '--light', c.light, '--camera', 'camera.json', '--depth', 'camera_depth.exr',
        '--medium', 'medium.json', '--method', 'volume', '--out', `${c.name}_homogeneous.exr`);
  run('render', c.volume, '--light', c.light, '--camera', 'camera.json',
      '--depth', c.noScene ? 'empty_depth.exr' : 'camera_depth.exr',
      '--medium', c.medium ?? 'medium.json', '--method', 'volume', '--out', `${c.name}_reference.exr`);
  // The composite's surfaces seen through the density: with --composite --background 1, render
  // adds each pixel's transmittance e^(−τ_E) to its surface; less the airlight, that alone.
  if (c.medium)
    run('render', c.volume, '--light', c.light, '--camera', 'camera.json', '--depth', 'camera_depth.exr',
        '--medium', c.medium, '--method', 'volume', '--composite', '--background', '1',
        '--out', `${c.name}_composite.exr`);
}

// ---- the browser ---------------------------------------------------------------------------------
const profile = mkdtempSync(join(tmpdir(), 'lightvol-chromium-'));
const { server, url } = await serve({ data: work });
const browser = await launchChromium(profile);
let failed = false;
try {
  for (const c of cases) {
    const page = await browser.newPage();
    await page.setViewport({ width: Math.max(camera.width, 480), height: camera.height + 90 });
    const messages = [];
    page.on('console', (m) => messages.push(m.text()));
    page.on('pageerror', (e) => messages.push(e.message));
    const address = url(`/web/index.html?volume=/data/${c.volume}&camera=/data/camera.json` +
                        `&medium=/data/${c.medium ?? 'medium.json'}` + (c.noScene ? '' : '&scene=/data/scene.glb'));
    const started = Date.now();
    await page.goto(address);
    await page.waitForFunction(() => document.title.startsWith('lightvol:') &&
                                     document.title !== 'lightvol viewer', { timeout: 300000 });
    const title = await page.title();
    if (c.error) {
      // Bad input: the page says what is wrong (status line and console), never a silent image.
      const status = await page.evaluate(() => document.getElementById('status').textContent);
      const ok = title === 'lightvol:error' && c.error.test(status) && messages.some((m) => c.error.test(m));
      console.log(`${c.name}: ${title}, the page says "${status}"` + (ok ? '' : `  FAILED (want ${c.error})`));
      if (!ok) failed = true;
      await page.close();
      continue;
    }
    if (title !== 'lightvol:done') {
      console.log(`${c.name}: the viewer failed (${title}): ${messages.join(' | ')}`);
      failed = true;
      await page.close();
      continue;
    }
    const airlight = Float32Array.from(await page.evaluate(() => Array.from(window.lightvolAirlight())));
    const surface = Float32Array.from(await page.evaluate(() => Array.from(window.lightvolSurface())));
    const counts = Float32Array.from(await page.evaluate(() => Array.from(window.lightvolFaceCounts())));
    // Two rasterizers (lightvol's OpenGL on llvmpipe, the browser's SwiftShader) may disagree on a
    // scene edge that runs through pixel centres: such pixels see different surfaces, so their
    // airlights differ for a reason that is not the volume. And the volume method needs watertight
    // rasterization: every pixel gets back faces minus front faces = 0 or 1 (camera inside) from a
    // closed volume; SwiftShader's guard-band clipping of long fan triangles can drop or double a
    // fragment on a shared edge. Both kinds of pixel are left out, counted, and must be rare (at
    // most 1 % of the image together).
    // Every pixel's ray starts at the camera, so a closed volume gives them all the same count: 1
    // with the camera inside, 0 outside; a pixel whose count is not the one most pixels have saw
    // a dropped or doubled fragment (a 0 or a 1 can be one too).
    const mask = new Uint8Array(airlight.length);
    let disagree = 0, cracks = 0;
    const inside = counts.filter((x) => x === 1).length > counts.length / 2 ? 1 : 0;
    for (let i = 0; i < mask.length; ++i) {
      const a = (c.noScene ? noSurface : lightvolSurface)[i], b = surface[i] >= 1e38 ? Infinity : surface[i];
      if (counts[i] !== inside) {
        mask[i] = 1;
        ++cracks;
      } else if (a !== b && !(Math.abs(a - b) <= 1e-3 * Math.min(a, b))) {
        mask[i] = 1;
        ++disagree;
      }
    }
    if (keep) writeFileSync(join(work, `${c.name}_viewer.f32`), Buffer.from(airlight.buffer));
    const reference = readExr(join(work, `${c.name}_reference.exr`));
    const info = await page.evaluate(() => document.getElementById('info').textContent);
    const l2 = airlight.length === reference.values.length ? relativeL2(airlight, reference.values, mask) : Infinity;
    let ok = l2 <= TOLERANCE && disagree + cracks <= 0.01 * mask.length;
    if (c.medium) {
      // The density must matter: the homogeneous medium's image is at least 5 % away.
      const homogeneous = readExr(join(work, `${c.name}_homogeneous.exr`)).values;
      const apart = relativeL2(airlight, homogeneous, mask);
      const matters = apart >= 0.05;
      console.log(`${c.name}: the homogeneous medium's render is ${(100 * apart).toFixed(1)} % away` +
                  (matters ? '' : '  FAILED (want >= 5 %: the case would not test the density)'));
      ok = ok && matters;
      // The composite dims the lit scene by the density's own transmittance (window.lightvolThrough),
      // as render --composite does: within 1 % of it where both see a surface, and at least 1 %
      // from the homogeneous e^(−σt·t) (the density matters there too).
      const through = Float32Array.from(await page.evaluate(() => Array.from(window.lightvolThrough())));
      const composite = readExr(join(work, `${c.name}_composite.exr`)).values;
      const expected = composite.map((x, i) => x - reference.values[i]);
      const sigmaT = (medium.scattering ?? 0) + (medium.absorption ?? 0);
      const flat = new Float32Array(through.length);
      const seen = Uint8Array.from(mask, (m, i) => (m || !(lightvolSurface[i] < Infinity) ? 1 : 0));
      for (let i = 0; i < flat.length; ++i) flat[i] = seen[i] ? 0 : Math.exp(-sigmaT * lightvolSurface[i]);
      const throughL2 = through.length === expected.length ? relativeL2(through, expected, seen) : Infinity;
      const throughApart = relativeL2(flat, expected, seen);
      const throughOk = throughL2 <= TOLERANCE && throughApart >= 0.01;
      console.log(`${c.name}: the composite's transmittance to the surfaces is ${(100 * throughL2).toFixed(4)} % ` +
                  `from render --composite's, the homogeneous one ${(100 * throughApart).toFixed(1)} %` +
                  (throughOk ? '' : '  FAILED (want <= 1 % and >= 1 %)'));
      ok = ok && throughOk;
    }
    console.log(`${c.name}: relative L2 ${(100 * l2).toFixed(4)} % against lightvol render --method volume ` +
                `(${reference.width}x${reference.height}, left out: ${disagree} pixels whose scene surfaces differ, ${cracks} whose face count is not the camera's ${inside}; ${info}; page ${((Date.now() - started) / 1000).toFixed(1)} s)` +
                (ok ? '' : '  FAILED'));
    if (!ok) failed = true;
    if (c.name === 'static') {
      // The controls: the airlight is linear in the intensity, so doubling the slider doubles the
      // frame; the wireframe toggle and an orbit drag re-render without an error.
      const after = await page.evaluate(() => {
        const slider = document.getElementById('intensity');
        slider.value = String(2 * Number(slider.value));
        slider.dispatchEvent(new Event('input'));
        const doubled = Array.from(window.lightvolCurrentAirlight());
        const box = document.getElementById('wireframe');
        box.checked = true;
        box.dispatchEvent(new Event('change'));
        return doubled;
      });
      const twice = airlight.map((x) => 2 * x);
      const linear = relativeL2(Float32Array.from(after), twice, new Uint8Array(twice.length));
      const canvas = await page.$('#view');
      const b = await canvas.boundingBox();
      await page.mouse.move(b.x + b.width / 2, b.y + b.height / 2);
      await page.mouse.down();
      await page.mouse.move(b.x + b.width / 2 + 1, b.y + b.height / 2, { steps: 1 });
      await page.mouse.up();
      const orbited = Float32Array.from(await page.evaluate(() => Array.from(window.lightvolCurrentAirlight())));
      const moved = relativeL2(orbited, Float32Array.from(after), new Uint8Array(twice.length));
      const controlsOk = linear <= 1e-5 && moved > 1e-3 && messages.every((m) => !/error/i.test(m));
      console.log(`${c.name} controls: intensity x2 gives the airlight x2 within ${linear.toExponential(1)}; ` +
                  `an orbit drag changes it by ${(100 * moved).toFixed(1)} %` + (controlsOk ? '' : '  FAILED'));
      if (!controlsOk) failed = true;
    }
    if (screenshot && c.name === 'static') {
      const canvas = await page.$('body');
      await canvas.screenshot({ path: screenshot });
      console.log(`screenshot: ${screenshot}`);
    }
    await page.close();
  }
} finally {
  await browser.close();
  server.close();
  rmSync(profile, { recursive: true, force: true });
  if (!keep) rmSync(work, { recursive: true, force: true });
}
process.exit(failed ? 1 : 0);
