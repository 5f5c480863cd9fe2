// A static file server for the browser test, the example and the benchmark page, on
// localhost only:
//   /            web/               (the package: dist/, example/, test/, bench/)
//   /modules/    web/node_modules/  (three, three-vrm; the pages' import map points here)
//   /testdata/   ../shared/testdata/
//   /oracles/    ../shared/oracles/ (the spec hook; no node_modules)
//   /demo/       web/dist/demo/     (demo.glb and demo.rig.toml by `tassel demo --out web/dist/demo`)
//   /testdata.json  the VRM files of ../shared/testdata/vrm
// `node test/serve.mjs [PORT]` serves until stopped; `start(port)` is the module's API.
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const shared = path.resolve(web, '../../shared');
const roots = [
  ['/modules/', path.join(web, 'node_modules')],
  ['/testdata/', path.join(shared, 'testdata')],
  ['/oracles/', path.join(shared, 'oracles')],
  ['/demo/', path.join(web, 'dist/demo')],
  ['/', web],
];
const types = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.wasm': 'application/wasm', '.json': 'application/json', '.css': 'text/css',
  '.vrm': 'application/octet-stream', '.glb': 'model/gltf-binary', '.toml': 'text/plain; charset=utf-8',
  '.png': 'image/png',
};

function resolve(urlPath) {
  for (const [prefix, dir] of roots) {
    if (urlPath.startsWith(prefix)) {
      const file = path.resolve(dir, '.' + decodeURIComponent(urlPath.slice(prefix.length - 1)));
      // Inside its folder only.
      if (file !== dir && !file.startsWith(dir + path.sep)) return null;
      return file;
    }
  }
  return null;
}

export function start(port = 0) {
  const server = http.createServer((req, res) => {
    const urlPath = new URL(req.url, 'http://localhost').pathname;
    if (urlPath === '/testdata.json') {
      const dir = path.join(shared, 'testdata/vrm');
      const files = fs.existsSync(dir) ? fs.readdirSync(dir).filter((f) => f.endsWith('.vrm')).sort() : [];
      res.writeHead(200, { 'content-type': types['.json'] });
      res.end(JSON.stringify(files.map((f) => `/testdata/vrm/${f}`)));
      return;
    }
    let file = resolve(urlPath);
    if (file && fs.existsSync(file) && fs.statSync(file).isDirectory()) file = path.join(file, 'index.html');
    if (!file || !fs.existsSync(file)) {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end(`not found: ${urlPath}`);
      return;
    }
    res.writeHead(200, { 'content-type': types[path.extname(file)] ?? 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  return new Promise((ok) => server.listen(port, '127.0.0.1', () => ok(server)));
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const server = await start(Number(process.argv[2] ?? 8765));
  const { port } = server.address();
  console.log(`tassel-three: http://127.0.0.1:${port}/example/ (Ctrl-C stops)`);
}
