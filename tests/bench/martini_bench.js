// node martini_bench.js MARTINI_DIR MAP.f32 N OUT_PREFIX E1 [E2 ...]
// Runs Mapbox Martini (RTIN) on the map: one createTile, then getMesh per bound. Prints one line per
// bound: "bound E triangles T ms_tile A ms_mesh B" and writes OUT_PREFIX<i>.mrt (uint32 vertex and
// triangle counts, uint32 x y pairs, uint32 index triples) for heightfield_tool's error measure.
'use strict';
const fs = require('fs');
const path = require('path');
const [dir, mapPath, nText, prefix, ...bounds] = process.argv.slice(2);
const Martini = require(path.join(dir, 'node_modules/@mapbox/martini')).default ||
                require(path.join(dir, 'node_modules/@mapbox/martini'));
const n = Number(nText);
const buf = fs.readFileSync(mapPath);
const terrain = new Float32Array(buf.buffer, buf.byteOffset, n * n);
let t0 = process.hrtime.bigint();
const martini = new Martini(n);
const tile = martini.createTile(terrain);
const tileMs = Number(process.hrtime.bigint() - t0) / 1e6;
bounds.forEach((b, i) => {
  t0 = process.hrtime.bigint();
  const mesh = tile.getMesh(Number(b));
  const meshMs = Number(process.hrtime.bigint() - t0) / 1e6;
  const nv = mesh.vertices.length / 2, nt = mesh.triangles.length / 3;
  const out = Buffer.alloc(8 + 8 * nv + 12 * nt);
  out.writeUInt32LE(nv, 0);
  out.writeUInt32LE(nt, 4);
  for (let k = 0; k < 2 * nv; ++k) out.writeUInt32LE(mesh.vertices[k], 8 + 4 * k);
  for (let k = 0; k < 3 * nt; ++k) out.writeUInt32LE(mesh.triangles[k], 8 + 8 * nv + 4 * k);
  fs.writeFileSync(prefix + i + '.mrt', out);
  console.log(`bound ${b} triangles ${nt} ms_tile ${tileMs.toFixed(1)} ms_mesh ${meshMs.toFixed(1)}`);
});
