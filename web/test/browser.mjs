// tassel-three in a real browser: headless Chromium (Debian's /usr/bin/chromium, driven
// by playwright-core) opens
//   - test/browser/parity.html, which runs the parity of test/parity.mjs with three.js,
//     three-vrm and the WebAssembly module as a web app does;
//   - example/demo.html?test=1: demo.glb's character (from `tassel demo --out
//     web/dist/demo`, which .ci/run runs) played by three.js's AnimationMixer with its
//     chains, skirt cloth, rope and springs live in WebAssembly, 600 frames: every frame
//     steps, nothing is NaN, every written bone keeps its length, the bones swing.
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import { start } from './serve.mjs';

const executablePath = process.env.CHROMIUM ?? '/usr/bin/chromium';
if (!fs.existsSync(executablePath)) {
  console.log(`FAIL: no Chromium at ${executablePath} (apt-get install chromium; .ci/run does)`);
  process.exit(1);
}
const server = await start(0);
const { port } = server.address();
const browser = await chromium.launch({
  executablePath,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
let failures = 0;
try {
  const page = await browser.newPage();
  page.on('pageerror', (e) => { console.log(`FAIL page error: ${e.message}`); failures++; });
  await page.goto(`http://127.0.0.1:${port}/test/browser/parity.html`);
  await page.waitForFunction(() => window.tasselResult !== undefined, null, { timeout: 600_000 });
  const result = await page.evaluate(() => window.tasselResult);
  for (const line of result.lines) console.log(line);
  console.log(`(${result.userAgent})`);
  failures += result.failures;
  if (result.files === 0 && process.env.TASSEL_REQUIRE_TESTDATA) {
    console.log('FAIL: no test files reached the page and TASSEL_REQUIRE_TESTDATA is set');
    failures++;
  }
  const demo = new URL('../dist/demo/demo.glb', import.meta.url);
  if (!fs.existsSync(demo)) {
    console.log(`FAIL: ${demo.pathname} is missing: run \`target/release/tassel demo --out web/dist/demo\` after web/build.sh`);
    failures++;
  } else {
    const page = await browser.newPage();
    page.on('pageerror', (e) => { console.log(`FAIL demo page error: ${e.message}`); failures++; });
    await page.goto(`http://127.0.0.1:${port}/example/demo.html?test=1`);
    await page.waitForFunction(() => window.tasselDemo !== undefined, null, { timeout: 300_000 });
    const r = await page.evaluate(() => window.tasselDemo);
    console.log(`demo: ${r.bones} bones stepped by Tassel over ${r.frames} frames; bone lengths kept to ${r.worstLength.toExponential(2)} m (the spring controller's ${r.moved.join(', ')} move by design); largest swing from rest ${r.largestSwing.toFixed(3)} rad`);
    if (r.springBones.length !== 2 || r.moved.length !== 2) { console.log(`FAIL demo: the rig's springs ${r.springBones} are not the two chest bones`); failures++; }
    for (const f of r.failed.slice(0, 10)) console.log(`FAIL demo ${f}`);
    failures += r.failed.length;
    if (r.bones < 20) { console.log('FAIL demo: fewer than 20 bones stepped'); failures++; }
    if (r.frames !== 600) { console.log('FAIL demo: not every frame ran'); failures++; }
    if (!(r.worstLength <= 1e-4)) { console.log('FAIL demo: a bone changed its length'); failures++; }
    if (!(r.largestSwing > 0.1)) { console.log('FAIL demo: the bones did not swing'); failures++; }
  }
} finally {
  await browser.close();
  server.close();
}
console.log(failures ? `browser parity: ${failures} FAILED` : 'browser parity: all passed');
process.exit(failures ? 1 : 0);
