// tassel-three in a real browser: headless Chromium (Debian's /usr/bin/chromium, driven
// by playwright-core) opens test/browser/parity.html, which runs the parity of
// test/parity.mjs with three.js, three-vrm and the WebAssembly module as a web app does.
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
} finally {
  await browser.close();
  server.close();
}
console.log(failures ? `browser parity: ${failures} FAILED` : 'browser parity: all passed');
process.exit(failures ? 1 : 0);
