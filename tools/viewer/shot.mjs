// Screenshots of a GLB (default: demo.glb beside this file) through three.js in headless
// Chromium (software GL): `node shot.mjs [file.glb] [t,side ...]`, e.g. `3.75,1` is the
// clip at 3.75 s seen from the side (`0`: from behind and above). Needs Debian's
// chromium (/usr/bin/chromium) and `npm install` here. Writes shot_<t>.png here.
import { chromium } from 'playwright-core';
import { createServer } from 'node:http';
import { readFile, copyFile } from 'node:fs/promises';
import { dirname, join, extname } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const glb = args[0] && args[0].endsWith('.glb') ? args.shift() : null;
if (glb) await copyFile(glb, join(here, 'demo.glb'));
const shots = (args.length ? args : ['0.5,0', '3.75,1', '7.45,1', '12.2,0', '16.3,0']).map((s) => s.split(','));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.glb': 'model/gltf-binary' };
const server = createServer(async (req, res) => {
  try {
    const path = join(here, decodeURIComponent(new URL(req.url, 'http://x').pathname));
    const body = await readFile(path);
    res.writeHead(200, { 'Content-Type': types[extname(path)] || 'application/octet-stream' });
    res.end(body);
  } catch {
    res.writeHead(404);
    res.end();
  }
}).listen(0, '127.0.0.1');
await new Promise((r) => server.once('listening', r));
const port = server.address().port;
const browser = await chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
});
const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
for (const [t, side] of shots) {
  await page.goto(`http://127.0.0.1:${port}/index.html?t=${t}&side=${side}`);
  await page.waitForFunction(() => document.title.length > 0, null, { timeout: 60000 });
  const title = await page.title();
  if (title !== 'done') throw new Error(`t = ${t}: ${title}`);
  await page.screenshot({ path: join(here, `shot_${t}.png`) });
  console.log(`shot_${t}.png`);
}
await browser.close();
server.close();
