// The live page's adaptive volumes (web/live.html?adaptive=E: LightVolume's maxError,
// web/live_adaptive.js) in a real browser: Debian's chromium, headless, WebGL2 on SwiftShader. For a
// spot, a directional and a point (omni) light on `lightvol demo`'s scene with animate=1, frames 0
// and 30: the page's triangles (read back by transform feedback of the vertex stages that draw
// them) make a closed, consistently wound surface whose grid covers every texel of the map (omni:
// of the six faces); the bound E holds at every texel (TexelDepths' measure, in double, texel by
// texel against the triangle that covers it; omni: each face's own view); the count is within 5 %
// of `lightvol build --adaptive --max-error E --tessellation quadtree` of the page's own map and
// light; the fix-up rounds (and omni seam rounds) converged; the airlight is within 1 % relative
// L2 of `lightvol render --method volume` of build's adaptive volume; the two frames differ. Bad
// input: an E that is not a number >= 0, a count that is neither: the message on the page.
//   node web/tests/live_adaptive_test.mjs PATH/TO/lightvol [--only spot|directional|omni|errors] [--size N]
//                                         [--screenshot DIR] [--keep DIR]
// Exit 0 when every case passes, 1 when one fails, 2 when something could not run.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { serve } from '../serve.mjs';
import { DEMO_LIGHTS, launchChromium, readExr, relativeL2, writePfm } from './support.mjs';

const args = process.argv.slice(2);
const lightvol = args[0] && resolve(args[0]);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : fallback;
};
if (!lightvol || !existsSync(lightvol)) {
  console.error('usage: live_adaptive_test.mjs PATH/TO/lightvol [--only CASE] [--size N] [--screenshot DIR] [--keep DIR]');
  process.exit(2);
}
const size = Number(option('--size', 96));
const screenshots = option('--screenshot', null);
const keep = option('--keep', null);
const only = option('--only', null);
const TOLERANCE = 0.01;
// The bounds (world units along the texel rays; the demo's scene is about 20 units across): a
// bound at which build's quadtree needs a fix-up round on these 96² maps (omni: six 48² faces)
// (asserted: the rounds are exercised); a fine one; a very coarse one whose airlight differs from
// the static volume's by more than 2 % (asserted: the test sees the adaptive volume in the picture,
// not only in the triangles; omni: the atrium's airlight moves by 0.3 % up to E = 52 and by 15 % at
// E = 55, where each face is its two root triangles). Omni bounds with `seams` need at least 2 of
// build's seam rounds (asserted; 5 and 6 on these maps).
// count: 'bound' draws the grid sized by the static volume's count, no read-back (the others: the
// count pyramid's total, read back).
const CASES = [{ name: 'spot', e: 0.5, fixup: true }, { name: 'spot', e: 5, distinct: true },
               { name: 'directional', e: 0.5, fixup: true }, { name: 'directional', e: 0.01, count: 'bound' },
               { name: 'omni', e: 0.3, fixup: true, seams: true }, { name: 'omni', e: 5, seams: true, count: 'bound' },
               { name: 'omni', e: 60, distinct: true, still: 0.005 }];
if (option('--max-error', null) !== null)
  for (const c of CASES) Object.assign(c, { e: Number(option('--max-error', null)), fixup: false });

const work = keep ? resolve(keep) : mkdtempSync(join(tmpdir(), 'lightvol-adaptive-'));
mkdirSync(work, { recursive: true });
if (screenshots) mkdirSync(resolve(screenshots), { recursive: true });
const run = (...a) => execFileSync(lightvol, [...a, '--quiet'], { cwd: work, stdio: ['ignore', 'ignore', 'inherit'] });

run('demo', '--out', '.', '--size', '128');
const camera = JSON.parse(readFileSync(join(work, 'camera.json'), 'utf8'));
writeFileSync(join(work, 'camera_radial.json'), JSON.stringify({ ...camera, depth: 'radial' }));
const lights = { spot: JSON.parse(readFileSync(join(work, 'light.json'), 'utf8')), ...DEMO_LIGHTS };
for (const [name, json] of Object.entries(lights)) writeFileSync(join(work, `light_${name}.json`), JSON.stringify(json));

// ---- TexelDepths (src/lightvol/tessellate/texel_depths.cpp) in double ----------------------------

function inverse(a) {  // row-major 4 × 4, Gauss-Jordan with partial pivoting
  const m = [0, 1, 2, 3].map((r) => [...a.slice(4 * r, 4 * r + 4), ...[0, 1, 2, 3].map((c) => (c === r ? 1 : 0))]);
  for (let c = 0; c < 4; ++c) {
    let p = c;
    for (let r = c + 1; r < 4; ++r) if (Math.abs(m[r][c]) > Math.abs(m[p][c])) p = r;
    [m[c], m[p]] = [m[p], m[c]];
    const s = m[c][c];
    for (let k = 0; k < 8; ++k) m[c][k] /= s;
    for (let r = 0; r < 4; ++r)
      if (r !== c) {
        const f = m[r][c];
        for (let k = 0; k < 8; ++k) m[r][k] -= f * m[c][k];
      }
  }
  return m.flatMap((row) => row.slice(4));
}
const multiply = (a, b) => Array.from({ length: 16 }, (_, i) => {
  const r = i >> 2, c = i & 3;
  return a[4 * r] * b[c] + a[4 * r + 1] * b[4 + c] + a[4 * r + 2] * b[8 + c] + a[4 * r + 3] * b[12 + c];
});

// An omni light's face f as lightvol sees it (omni_face_view, perspective(90°, 1, near, far)).
function omniFace(light, f) {
  const look = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]][f];
  const up = [[0, -1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0], [0, -1, 0]][f];
  const norm = (v) => { const l = Math.hypot(...v); return v.map((x) => x / l); };
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const e = light.position, fw = norm(look), sd = norm(cross(fw, up)), uu = cross(sd, fw);
  const view = [[...sd, -dot(sd, e)], [...uu, -dot(uu, e)], [-fw[0], -fw[1], -fw[2], dot(fw, e)], [0, 0, 0, 1]];
  const t = 1 / Math.tan(90 * Math.PI / 360), { near, far } = light;
  return { view, projection: [[t, 0, 0, 0], [0, t, 0, 0], [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
                              [0, 0, -1, 0]] };
}

// The world distance along texel (col, row)'s ray between its depth and depth dp.
function texelError(light, map, width, height) {
  const m = multiply(inverse(light.view.flat()), inverse(light.projection.flat())), at = (r, c) => m[4 * r + c];
  const h1 = [0, 1, 2, 3].map((k) => 2 * at(k, 2));
  return (col, row, dp) => {
    const x = 2 * (col + 0.5) / width - 1, y = -(2 * (row + 0.5) / height - 1);
    const h0 = [0, 1, 2, 3].map((k) => at(k, 0) * x + at(k, 1) * y - at(k, 2) + at(k, 3));
    const d = Math.min(Math.max(map[row * width + col], 0), 1);
    const g = Math.hypot(h1[0] * h0[3] - h0[0] * h1[3], h1[1] * h0[3] - h0[1] * h1[3], h1[2] * h0[3] - h0[2] * h1[3]);
    return Math.abs(dp - d) * g / Math.abs(h0[3] + d * h1[3]) / Math.abs(h0[3] + dp * h1[3]);
  };
}

// The page's triangles: closed and consistently wound (every directed edge once, its reverse
// once), the grid's covering every texel, and the largest error over the texels of the grid's
// triangles (each texel against every triangle that holds it, edges and corners included). Omni:
// `map` holds the six faces one under the other; a grid triangle's vertices are of kind 8 + f.
function checkTriangles(triangles, light, map, width, height) {
  const faces = light.type === 'omni' ? 6 : 1;
  const errors = [], depths = [];
  for (let f = 0; f < faces; ++f) {
    const face = map.subarray(f * width * height, (f + 1) * width * height);
    errors.push(texelError(faces === 6 ? omniFace(light, f) : light, face, width, height));
    depths.push((c, r) => Math.min(Math.max(face[r * width + c], 0), 1));
  }
  const key = (v) => v.join(',');
  const edges = new Map();
  for (const t of triangles)
    for (let k = 0; k < 3; ++k) {
      const e = `${key(t[k])}>${key(t[(k + 1) % 3])}`;
      edges.set(e, (edges.get(e) ?? 0) + 1);
    }
  let closed = true;
  for (const [e, n] of edges) {
    const [a, b] = e.split('>');
    if (n !== 1 || edges.get(`${b}>${a}`) !== 1) closed = false;
  }
  const covered = new Uint8Array(faces * width * height);
  let worst = 0, grid = 0;
  for (const t of triangles) {
    const kind = t[0][0];
    if (!(kind === 1 || kind >= 8) || !t.every((v) => v[0] === kind)) continue;
    ++grid;
    const f = kind === 1 ? 0 : kind - 8, error = errors[f], depth = depths[f];
    const [[, ax, ay], [, bx, by], [, cx, cy]] = t;
    const area = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
    if (area === 0) { closed = false; continue; }
    const da = depth(ax, ay), db = depth(bx, by), dc = depth(cx, cy);
    for (let y = Math.min(ay, by, cy); y <= Math.max(ay, by, cy); ++y)
      for (let x = Math.min(ax, bx, cx); x <= Math.max(ax, bx, cx); ++x) {
        const beta = ((x - ax) * (cy - ay) - (cx - ax) * (y - ay)) / area;
        const gamma = ((bx - ax) * (y - ay) - (x - ax) * (by - ay)) / area;
        if (beta < 0 || gamma < 0 || beta + gamma > 1) continue;
        covered[(f * height + y) * width + x] = 1;
        worst = Math.max(worst, error(x, y, da + (db - da) * beta + (dc - da) * gamma));
      }
  }
  return { closed, worst, grid, uncovered: covered.reduce((n, c) => n + (c ? 0 : 1), 0) };
}

// ---- the browser ----------------------------------------------------------------------------------
const profile = mkdtempSync(join(tmpdir(), 'lightvol-chromium-'));
const { server, url } = await serve({ data: work });
const browser = await launchChromium(profile);

const grab = (page, hook) => page.evaluate((h) => {
  const v = window[h]();
  return ArrayBuffer.isView(v) ? Array.from(v) : v;
}, hook);

async function checkFrame(page, { name, e, fixup, seams, distinct, count }, frame) {
  const airlight = Float32Array.from(await grab(page, 'lightvolAirlight'));
  const map = Float32Array.from(await grab(page, 'lightvolShadowMap'));
  const light = await grab(page, 'lightvolLight');
  const medium = await grab(page, 'lightvolMedium');
  const surface = Float32Array.from(await grab(page, 'lightvolSurface'));
  const counts = Float32Array.from(await grab(page, 'lightvolFaceCounts'));
  const triangles = await grab(page, 'lightvolTriangles');
  const converged = await grab(page, 'lightvolConverged');
  if (keep) writeFileSync(join(work, `${name}_${e}_${frame}_triangles.json`), JSON.stringify(triangles));
  const tag = `${name}_${e}_${frame}`;
  // Omni: six faces of half the size, one under the other.
  const faces = light.type === 'omni' ? 6 : 1, width = faces === 6 ? size / 2 : size;
  const height = map.length / width / faces;
  writeFileSync(join(work, `${tag}_light.json`), JSON.stringify(light));
  writeFileSync(join(work, `${tag}_medium.json`), JSON.stringify(medium));
  writePfm(join(work, `${tag}_map.pfm`), map, width, faces * height);
  writePfm(join(work, `${tag}_surface.pfm`), surface.map((t) => (t >= 1e38 ? 1e30 : t)), camera.width, camera.height);
  run('build', `${tag}_map.pfm`, '--light', `${tag}_light.json`, '--adaptive', '--max-error', String(e),
      '--tessellation', 'quadtree', '--out', `${tag}_volume.off`, '--report', `${tag}_report.json`);
  const report = JSON.parse(readFileSync(join(work, `${tag}_report.json`), 'utf8'));
  const rounds = report.adaptive.fixup_rounds;
  // Omni: build's seam rounds (lightvol stats); `seams`: at least 2, so that the page's seam rounds
  // are exercised.
  let seamRounds = null;
  if (faces === 6) {
    const stats = JSON.parse(execFileSync(lightvol, ['stats', `${tag}_map.pfm`, '--light', `${tag}_light.json`, '--max-error',
                                                     String(e), '--tessellation', 'quadtree', '--json', '--quiet'],
                                          { cwd: work, encoding: 'utf8' }));
    seamRounds = stats.adaptive[0].seam_rounds;
  }
  const off = readFileSync(join(work, `${tag}_volume.off`), 'utf8').split('\n');
  const built = Number(off[1].split(' ')[1]);
  const { closed, worst, grid, uncovered } = checkTriangles(triangles, light, map, width, height);
  const within = Math.abs(triangles.length - built) <= 0.05 * built;
  run('render', `${tag}_volume.off`, '--light', `${tag}_light.json`, '--camera', 'camera_radial.json',
      '--depth', `${tag}_surface.pfm`, '--medium', `${tag}_medium.json`, '--method', 'volume', '--out', `${tag}_reference.exr`);
  const reference = readExr(join(work, `${tag}_reference.exr`));
  let fromStatic = null;
  if (distinct) {
    run('build', `${tag}_map.pfm`, '--light', `${tag}_light.json`, '--out', `${tag}_static.off`);
    run('render', `${tag}_static.off`, '--light', `${tag}_light.json`, '--camera', 'camera_radial.json',
        '--depth', `${tag}_surface.pfm`, '--medium', `${tag}_medium.json`, '--method', 'volume', '--out', `${tag}_static.exr`);
    fromStatic = relativeL2(reference.values, readExr(join(work, `${tag}_static.exr`)).values);
  }
  // As live_test.mjs: pixels whose face count shows SwiftShader dropped a fragment are left out.
  const inside = counts.filter((x) => x === 1).length > counts.length / 2 ? 1 : 0;
  const mask = counts.map((x) => (x === inside ? 0 : 1));
  const cracks = mask.reduce((a, b) => a + b, 0);
  const l2 = airlight.length === reference.values.length ? relativeL2(airlight, reference.values, mask) : Infinity;
  const lit = reference.values.filter((x) => x > 0).length;
  const ok = (!fixup || rounds >= 1) && (!seams || seamRounds >= 2) && (!distinct || fromStatic > 0.02) && closed && uncovered === 0 && worst <= e && within && converged && l2 <= TOLERANCE &&
             cracks <= 0.01 * mask.length && lit > 0.05 * mask.length && triangles.length < 0.5 * 2 * faces * width * height;
  console.log(`${name} frame ${frame}, E = ${e}${count ? ` (count=${count})` : ''}: ${triangles.length} triangles (${grid} grid), build's quadtree ${built} ` +
              `(${(100 * (triangles.length - built) / built).toFixed(2)} %, ${rounds} fix-up rounds` +
              `${faces === 6 ? `, ${seamRounds} seam rounds` : ''}); ${closed ? 'closed' : 'NOT closed'}, ` +
              `${uncovered} texels uncovered, largest texel error ${worst.toPrecision(6)} ` +
              `(${(worst / e).toFixed(6)} E), fix-up ${converged ? 'converged' : 'NOT converged'}; airlight ` +
              `${(100 * l2).toFixed(4)} % relative L2 against render --method volume of build's adaptive volume ` +
              `(${lit} pixels lit, ${cracks} left out)` +
              (distinct ? `; build's adaptive airlight ${(100 * fromStatic).toFixed(2)} % from its static one's` : '') +
              (ok ? '' : '  FAILED'));
  return { ok, airlight, map, triangles: triangles.length };
}

let failed = false;
try {
  for (const c of CASES) {
    const { name, e, count } = c;
    if (only && only !== name) continue;
    const started = Date.now();
    const page = await browser.newPage();
    await page.setViewport({ width: Math.max(camera.width, 480), height: camera.height + 60 });
    const messages = [];
    page.on('console', (m) => messages.push(m.text()));
    page.on('pageerror', (err) => messages.push(err.message));
    await page.goto(url(`/web/live.html?scene=/data/scene.glb&light=/data/light_${name}.json` +
                        `&medium=/data/medium.json&camera=/data/camera.json&animate=1&size=${name === 'omni' ? size / 2 : size}` +
                        `&adaptive=${e}` +
                        (count ? `&count=${count}` : '')));
    await page.waitForFunction(() => document.title.startsWith('lightvol:'), { timeout: 300000 });
    const title = await page.title();
    if (title !== 'lightvol:done') {
      console.log(`${name}: the page failed (${title}): ${messages.join(' | ')}  FAILED`);
      failed = true;
      await page.close();
      continue;
    }
    const first = await checkFrame(page, c, 0);
    if (screenshots) await page.screenshot({ path: join(resolve(screenshots), `live_adaptive_${name}_${e}_0.png`) });
    const frame = await page.evaluate(() => window.lightvolStep(30));
    const second = await checkFrame(page, c, frame);
    if (screenshots) await page.screenshot({ path: join(resolve(screenshots), `live_adaptive_${name}_${e}_30.png`) });
    let changed = 0, pixels = 0;
    for (let i = 0; i < first.map.length; ++i) if (first.map[i] !== second.map[i]) ++changed;
    for (let i = 0; i < first.airlight.length; ++i)
      if (Math.abs(first.airlight[i] - second.airlight[i]) > 0.01 * Math.abs(first.airlight[i])) ++pixels;
    // still: the share of pixels that must change, when not 1 %: at omni E = 60 the volume is each
    // face's two root triangles (its vertices the faces' corner texels) and the ball's move changes
    // 0.77 % of the pixels by more than 1 %, against 1.9 % at E = 0.3.
    const differ = frame === 30 && changed > 0.002 * first.map.length && pixels > (c.still ?? 0.01) * first.airlight.length;
    console.log(`${name}, E = ${e}: frames 0 and ${frame} differ in ${changed} of ${first.map.length} shadow-map texels and ` +
                `${pixels} of ${first.airlight.length} pixels; page ${((Date.now() - started) / 1000).toFixed(1)} s` +
                (differ ? '' : '  FAILED'));
    const quiet = messages.every((m) => !/error/i.test(m));
    if (!quiet) console.log(`${name}: console: ${messages.join(' | ')}  FAILED`);
    failed ||= !first.ok || !second.ok || !differ || !quiet;
    await page.close();
  }
  if (!only || only === 'errors') {
    for (const [light, e, pattern] of [['spot', '-1', /adaptive=-1: a bound E >= 0/],
                                       ['spot', '0.1&count=all', /count: expected 'readback' or 'bound', got all/]]) {
      const page = await browser.newPage();
      const messages = [];
      page.on('console', (m) => messages.push(m.text()));
      await page.goto(url(`/web/live.html?scene=/data/scene.glb&light=/data/light_${light}.json` +
                          `&medium=/data/medium.json&camera=/data/camera.json&size=16&adaptive=${e}`));
      await page.waitForFunction(() => document.title.startsWith('lightvol:'), { timeout: 300000 });
      const shown = await page.evaluate(() => document.getElementById('status').textContent);
      const ok = (await page.title()) === 'lightvol:error' && pattern.test(shown) && messages.some((m) => pattern.test(m));
      console.log(`errors: ${light} with adaptive=${e}: page says "${shown}"` + (ok ? '' : '  FAILED'));
      failed ||= !ok;
      await page.close();
    }
  }
} finally {
  await browser.close();
  server.close();
  rmSync(profile, { recursive: true, force: true });
  if (!keep) rmSync(work, { recursive: true, force: true });
}
process.exit(failed ? 1 : 0);
