// What the browser tests and the browser benchmarks share: Debian's chromium with WebGL2 on
// SwiftShader, and the images lightvol reads and writes.
import { readFileSync, writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';
import * as THREE from 'three';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';

// A directional and an omni light over `lightvol demo`'s scene (its spot light is the demo's own).
export const DEMO_LIGHTS = {
  directional: { type: 'directional', position: [0.5, 10.0, -6.5], direction: [0.2, -0.9, 1], up: [0, 1, 0],
                 ortho: [-5, 5, -5, 5], near: 0.1, far: 30.0 },
  omni: { type: 'omni', position: [0.5, 3.0, -1.0], near: 0.1, far: 40.0 },
};

// Headless chromium ($CHROMIUM, else /usr/bin/chromium) with WebGL2 on SwiftShader (float render
// targets and float blending work without a GPU), its profile in `profile`.
export function launchChromium(profile) {
  return puppeteer.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    args: ['--headless', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--disable-gpu', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', `--user-data-dir=${profile}`],
    userDataDir: profile,
  });
}

// A PFM image (one channel) of `values`, top row first: lightvol reads it through OpenImageIO;
// PFM stores rows bottom first.
export function writePfm(path, values, width, height) {
  const header = Buffer.from(`Pf\n${width} ${height}\n-1.0\n`, 'latin1');
  const body = Buffer.alloc(4 * width * height);
  for (let r = 0; r < height; ++r)
    for (let c = 0; c < width; ++c) body.writeFloatLE(values[(height - 1 - r) * width + c], 4 * (r * width + c));
  writeFileSync(path, Buffer.concat([header, body]));
}

// An EXR image (lightvol render --out X.exr): its first channel, top row first. three's EXRLoader
// returns RGBA rows bottom row first.
export function readExr(path) {
  const bytes = readFileSync(path);
  const loader = new EXRLoader();
  loader.setDataType(THREE.FloatType);
  const image = loader.parse(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length));
  const { width: w, height: h, data: rgba } = image;
  const channels = rgba.length / (w * h);
  const values = new Float32Array(w * h);
  for (let r = 0; r < h; ++r)
    for (let c = 0; c < w; ++c) values[r * w + c] = rgba[((h - 1 - r) * w + c) * channels];
  return { width: w, height: h, values };
}

// ‖a − ref‖ / ‖ref‖ over the pixels where `mask` (if given) is 0.
export function relativeL2(a, ref, mask = null) {
  let d = 0, n = 0;
  for (let i = 0; i < ref.length; ++i) {
    if (mask && mask[i]) continue;
    d += (a[i] - ref[i]) ** 2;
    n += ref[i] ** 2;
  }
  return Math.sqrt(d) / Math.sqrt(n);
}
