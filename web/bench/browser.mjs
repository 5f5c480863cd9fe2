// `node bench/browser.mjs [avatar] [FRAMES] [RUNS]`: bench/index.html in headless Chromium
// (Debian's /usr/bin/chromium): three-vrm's spring update against Tassel's, side by side in
// the page, on the bench rig or (`avatar`) Tassel's built-in avatar.
import { chromium } from 'playwright-core';
import { start } from '../test/serve.mjs';

const args = process.argv.slice(2);
const avatar = args[0] === 'avatar' ? args.shift() : null;
const frames = Number(args[0] ?? 400);
const runs = Number(args[1] ?? 11);
const server = await start(0);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
try {
  const page = await browser.newPage();
  page.on('console', (m) => console.log(m.text()));
  page.on('pageerror', (e) => console.log(`page error: ${e.message}`));
  await page.goto(`http://127.0.0.1:${server.address().port}/bench/?frames=${frames}&runs=${runs}${avatar ? '&avatar=1' : ''}`);
  await page.waitForFunction(() => window.tasselBench !== undefined, null, { timeout: 900_000 });
  const { rows, userAgent } = await page.evaluate(() => window.tasselBench);
  console.log(userAgent);
  for (const r of rows) {
    const others = Object.keys(r.speedup).map((k) => `${k} ${r[k].toFixed(1)} (${r.speedup[k].toFixed(1)}x)`);
    console.log(`${r.characters} x ${r.joints} joints: three-vrm ${r['three-vrm 3.5.5'].toFixed(1)} ns/joint; ${others.join(', ')}`);
  }
} finally {
  await browser.close();
  server.close();
}
