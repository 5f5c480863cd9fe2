// `npm run bench --prefix web [-- FILE|avatar]`: the Node benchmark (bench.mjs, on FILE or
// Tassel's built-in avatar when one is given) and then the browser one (browser.mjs, on the
// bench rig or the built-in avatar: a file from the disk is measured in Node only).
import { spawnSync } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
// A file named relative to where npm was run (npm runs the script in web/).
const args = process.argv.slice(2).map((a, i) =>
  i === 0 && a !== 'avatar' && !/^[0-9,]+$/.test(a) ? path.resolve(process.env.INIT_CWD ?? process.cwd(), a) : a);
const browserArgs = args.filter((a) => a === 'avatar' || /^[0-9,]+$/.test(a));
for (const [script, rest] of [['bench.mjs', args], ['browser.mjs', browserArgs]]) {
  const r = spawnSync(process.execPath, [path.join(here, script), ...rest], { stdio: 'inherit' });
  if (r.status !== 0) process.exit(r.status ?? 1);
}
