// The example as the README gives it: `npm run example --prefix web`, run from the
// repository's root exactly as written, serves the page; headless Chromium opens the URL
// it prints and waits for the page to be ready: no page error, the built-in avatar (made by
// the WebAssembly module) stepping, and (with ../shared beside the clone) a test file too.
import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const executablePath = process.env.CHROMIUM ?? '/usr/bin/chromium';
if (!fs.existsSync(executablePath)) {
  console.log(`FAIL: no Chromium at ${executablePath} (apt-get install chromium; .ci/run does)`);
  process.exit(1);
}
// detached: its own process group, so that npm and the node it starts stop together.
const server = spawn('npm', ['run', 'example', '--prefix', 'web'], { cwd: root, detached: true });
let failures = 0;
let log = '';
const stop = () => { try { process.kill(-server.pid, 'SIGTERM'); } catch { /* gone */ } };
try {
  const url = await new Promise((ok, fail) => {
    const timer = setTimeout(() => fail(new Error(`no URL within 60 s:\n${log}`)), 60_000);
    const read = (chunk) => {
      log += chunk;
      const m = log.match(/http:\/\/127\.0\.0\.1:\d+\/example\//);
      if (m) { clearTimeout(timer); ok(m[0]); }
    };
    server.stdout.on('data', read);
    server.stderr.on('data', read);
    server.on('exit', (code) => { clearTimeout(timer); fail(new Error(`npm run example exited (${code}):\n${log}`)); });
  });
  console.log(`npm run example --prefix web: ${url}`);
  const browser = await chromium.launch({
    executablePath,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
  try {
    const page = await browser.newPage();
    page.on('pageerror', (e) => { console.log(`FAIL example page error: ${e.message}`); failures++; });
    await page.goto(url);
    await page.waitForFunction(() => window.tasselExampleReady === true, null, { timeout: 120_000 });
    // A frame or two after a file loaded: the panel names it with both engines' times.
    await page.waitForTimeout(1000);
    const text = await page.evaluate(() => document.getElementById('times').textContent);
    console.log(`example page: ${text}`);
    // The built-in avatar first, made by the module: no file needed. Its 44 spring
    // joints are counted from the character (13 strands; see builtin_avatar.rs).
    if (!/^Tassel's character: 44 spring bones · update: Tassel [0-9.]+ ms/.test(text)) {
      console.log('FAIL example: the built-in avatar is not stepping on the page');
      failures++;
    }
    // With ../shared beside the clone, a test file from the list steps too.
    if (fs.existsSync(path.join(root, '../shared/testdata/vrm'))) {
      await page.selectOption('#file', { label: 'smoke_spring.vrm' });
      await page.waitForFunction(() => /^smoke_spring\.vrm: \d+ spring bones · update: Tassel [0-9.]+ ms/
        .test(document.getElementById('times').textContent), null, { timeout: 30_000 });
      console.log(`example page: ${await page.evaluate(() => document.getElementById('times').textContent)}`);
    }
  } finally {
    await browser.close();
  }
} catch (e) {
  console.log(`FAIL example: ${e.message}`);
  failures++;
} finally {
  stop();
}
console.log(failures ? `example: ${failures} FAILED` : 'example: all passed');
process.exit(failures ? 1 : 0);
