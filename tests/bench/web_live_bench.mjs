// Frame times of the live page (web/live.html, LightVolume) in headless chromium, one table in one
// run: the demo's scene and 480×360 camera, the demo's spot, a directional and an omni light, for
// several shadow-map sizes, static volumes and adaptive ones (live.html?adaptive=E: build's quadtree
// at E made on the GPU every frame, web/live_adaptive.js) side by side; per row the whole frame
// (shadow map, lit scene, volume and airlight, composite) and the live volume with its airlight
// alone (for adaptive rows with the quadtree's passes), each frame waited for
// (window.lightvolTime). On SwiftShader (no GPU) these are a CPU rasterizer's times.
//   node tests/bench/web_live_bench.mjs PATH/TO/lightvol [FRAMES] [E] [ONLY] [COUNT]
// (ONLY: rows whose light, size and kind, e.g. "spot 512" or "spot 512 adaptive", start with it;
// COUNT: the adaptive rows'
// count=, readback (the default) or bound.)
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const [lightvolArg, framesArg, boundArg, onlyArg, countArg] = process.argv.slice(2);
if (!lightvolArg) {
  console.error('usage: web_live_bench.mjs PATH/TO/lightvol [FRAMES] [E] [ONLY] [COUNT]');
  process.exit(2);
}
const web = fileURLToPath(new URL('../../web', import.meta.url));
const { serve } = await import(pathToFileURL(join(web, 'serve.mjs')).href);
const { DEMO_LIGHTS, launchChromium } = await import(pathToFileURL(join(web, 'tests', 'support.mjs')).href);
const frames = Number(framesArg ?? 3);
const bound = Number(boundArg ?? 0.01);  // world units; the demo's scene is about 20 across
const work = mkdtempSync(join(tmpdir(), 'lightvol-live-bench-'));
execFileSync(resolve(lightvolArg), ['demo', '--out', work, '--size', '512', '--quiet']);
writeFileSync(join(work, 'light_directional.json'), JSON.stringify(DEMO_LIGHTS.directional));
writeFileSync(join(work, 'light_omni.json'), JSON.stringify(DEMO_LIGHTS.omni));
const camera = JSON.parse(readFileSync(join(work, 'camera.json'), 'utf8'));
const rows = [];
for (const [file, name, size] of [['light', 'spot', 256], ['light', 'spot', 512], ['light', 'spot', 1024], ['light', 'spot', 2048],
                                  ['light_directional', 'directional', 512],
                                  ['light_directional', 'directional', 1024]])
  rows.push([file, name, size, null], [file, name, size, bound]);
rows.push(['light_omni', 'omni', 256, null], ['light_omni', 'omni', 512, null]);
const { server, url } = await serve({ data: work });
const profile = mkdtempSync(join(tmpdir(), 'lightvol-chromium-'));
const browser = await launchChromium(profile);
try {
  console.log(`camera ${camera.width}x${camera.height}, ${frames} frames a row`);
  console.log('| light, map | volume | triangles | whole frame | volume + airlight | of which quadtree passes |\n|---|---|---|---|---|---|');
  for (const [file, name, size, e] of rows) {
    if (onlyArg && !`${name} ${size} ${e === null ? 'static' : 'adaptive'}`.startsWith(onlyArg)) continue;
    const page = await browser.newPage();
    await page.goto(url(`/web/live.html?scene=/data/scene.glb&light=/data/${file}.json&medium=/data/medium.json` +
                        `&camera=/data/camera.json&animate=1&size=${size}${e === null ? '' : `&adaptive=${e}`}` +
                        (e !== null && countArg ? `&count=${countArg}` : '')));
    await page.waitForFunction(() => document.title.startsWith('lightvol:'), { timeout: 900000 });
    if ((await page.title()) !== 'lightvol:done') throw new Error(`${name} ${size}: the page failed`);
    const t = await page.evaluate((n) => window.lightvolTime(n), frames);
    const map = name === 'omni' ? `6 × ${size}²` : `${size}²`;
    const kind = e === null ? 'static' : `adaptive, E = ${e}${countArg ? `, count=${countArg}` : ''}`;
    console.log(`| ${name}, ${map} | ${kind} | ` +
                `${t.triangles.toLocaleString('en')} | ${(t.frame / 1000).toFixed(2)} s | ` +
                `${(t.volume / 1000).toFixed(2)} s | ${t.passes === null ? '' : `${(t.passes / 1000).toFixed(2)} s` +
                `${t.rounds === null || t.rounds === undefined ? '' : ` (${t.rounds} fix-up rounds)`}`} |`);
    await page.close();
  }
} finally {
  await browser.close();
  server.close();
  rmSync(work, { recursive: true, force: true });
  rmSync(profile, { recursive: true, force: true });
}
