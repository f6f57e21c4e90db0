// A static file server for the viewer, on 127.0.0.1 only. The viewer needs its own folder, three.js
// from web/node_modules and ../shaders/airlight.glsl, so the repository root is served at /;
// a data folder (e.g. `lightvol demo`'s output) is served at /data/.
//   node web/serve.mjs [DATA_DIR] [--port N]      (port 0: any free port)
// Library use: serve({ root, data, port }) resolves to { server, port, url(path) }.
import { createServer } from 'node:http';
import { createReadStream } from 'node:fs';
import { stat } from 'node:fs/promises';
import { dirname, extname, join, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';

const TYPES = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.json': 'application/json', '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json',
  '.wasm': 'application/wasm', '.glsl': 'text/plain; charset=utf-8', '.png': 'image/png',
  '.ply': 'application/octet-stream', '.obj': 'text/plain', '.exr': 'application/octet-stream',
};
export const REPOSITORY = resolve(dirname(fileURLToPath(import.meta.url)), '..');

// The file under `base` that `relative` names, or null when it would leave `base`.
function inside(base, relative) {
  const path = resolve(base, '.' + sep + decodeURIComponent(relative));
  return path === base || path.startsWith(base + sep) ? path : null;
}

export function serve({ root = REPOSITORY, data = null, port = 0 } = {}) {
  root = resolve(root);
  data = data && resolve(data);
  const server = createServer(async (request, response) => {
    const path = new URL(request.url, 'http://127.0.0.1').pathname;
    let file = null;
    if (data && path.startsWith('/data/')) file = inside(data, path.slice('/data/'.length));
    else file = inside(root, path.slice(1));
    try {
      if (!file) throw new Error('outside');
      let info = await stat(file);
      if (info.isDirectory()) {
        file = join(file, 'index.html');
        info = await stat(file);
      }
      response.writeHead(200, { 'Content-Type': TYPES[extname(file).toLowerCase()] ?? 'application/octet-stream',
                                'Content-Length': info.size, 'Cache-Control': 'no-store' });
      createReadStream(file).pipe(response);
    } catch {
      response.writeHead(404, { 'Content-Type': 'text/plain' });
      response.end(`not found: ${path}\n`);
    }
  });
  return new Promise((done, fail) => {
    server.once('error', fail);
    server.listen(port, '127.0.0.1', () => {
      const actual = server.address().port;
      done({ server, port: actual, url: (p) => `http://127.0.0.1:${actual}${p}` });
    });
  });
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const args = process.argv.slice(2);
  let port = 8000, data = null;
  for (let i = 0; i < args.length; ++i) {
    if (args[i] === '--port') port = Number(args[++i]);
    else data = args[i];
  }
  const { url } = await serve({ data, port });
  console.log(`serving ${REPOSITORY} at ${url('/')}${data ? ` and ${resolve(data)} at ${url('/data/')}` : ''}`);
  if (data) {
    console.log(`open ${url('/web/index.html?volume=/data/volume_static.glb&camera=/data/camera.json' +
                          '&medium=/data/medium.json&scene=/data/scene.glb')}`);
    console.log(`  or ${url('/web/live.html?scene=/data/scene.glb&light=/data/light.json' +
                            '&medium=/data/medium.json&camera=/data/camera.json&animate=1')}`);
  }
}
