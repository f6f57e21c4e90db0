// node tin_bench.mjs SCRATCH_DIR martini|delatin MAP.f32 N OUT_PREFIX E1 [E2 ...]
// Runs Mapbox Martini (RTIN, @mapbox/martini) or Delatin (greedy Delaunay insertion, the JS port of
// hmm) on the N×N float32 height field: per bound, one line "bound E triangles T ms M" (Martini:
// createTile + getMesh; Delatin: constructor + run, from scratch for each bound) and OUT_PREFIX<i>.mrt
// (uint32 vertex and triangle counts, uint32 x y pairs, uint32 index triples) for heightfield_tool's
// shared error measure. The packages are installed by tessellation_bench.sh into SCRATCH_DIR.
import fs from 'fs';
import path from 'path';
import { createRequire } from 'module';
import { pathToFileURL } from 'url';

const [dir, mesher, mapPath, nText, prefix, ...bounds] = process.argv.slice(2);
const n = Number(nText);
const buf = fs.readFileSync(mapPath);
const terrain = new Float32Array(buf.buffer, buf.byteOffset, n * n);

function dump(file, coords, triangles) {
  const nv = coords.length / 2, nt = triangles.length / 3;
  const out = Buffer.alloc(8 + 8 * nv + 12 * nt);
  out.writeUInt32LE(nv, 0);
  out.writeUInt32LE(nt, 4);
  for (let k = 0; k < 2 * nv; ++k) out.writeUInt32LE(coords[k], 8 + 4 * k);
  for (let k = 0; k < 3 * nt; ++k) out.writeUInt32LE(triangles[k], 8 + 8 * nv + 4 * k);
  fs.writeFileSync(file, out);
  return nt;
}

if (mesher === 'martini') {
  const require = createRequire(import.meta.url);
  const mod = require(path.join(dir, 'node_modules/@mapbox/martini'));
  const Martini = mod.default || mod;
  let t0 = process.hrtime.bigint();
  const tile = new Martini(n).createTile(terrain);
  const tileMs = Number(process.hrtime.bigint() - t0) / 1e6;
  bounds.forEach((b, i) => {
    t0 = process.hrtime.bigint();
    const mesh = tile.getMesh(Number(b));
    const ms = tileMs + Number(process.hrtime.bigint() - t0) / 1e6;
    const nt = dump(prefix + i + '.mrt', mesh.vertices, mesh.triangles);
    console.log(`bound ${b} triangles ${nt} ms ${ms.toFixed(0)}`);
  });
} else {
  const { default: Delatin } =
      await import(pathToFileURL(path.join(dir, 'node_modules/delatin/index.js')).href);
  bounds.forEach((b, i) => {
    const t0 = process.hrtime.bigint();
    const tin = new Delatin(terrain, n, n);
    tin.run(Number(b));
    const ms = Number(process.hrtime.bigint() - t0) / 1e6;
    const nt = dump(prefix + i + '.mrt', tin.coords, tin.triangles);
    console.log(`bound ${b} triangles ${nt} ms ${ms.toFixed(0)}`);
  });
}
