// The package as npm would publish it (`npm pack --dry-run`): its README, its module, its
// types and its WebAssembly, and nothing else of dist/ (not the demo files the browser
// test serves from there).
import { execFileSync } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const out = execFileSync('npm', ['pack', '--dry-run', '--json'], { cwd: web, encoding: 'utf8' });
const files = JSON.parse(out)[0].files.map((f) => f.path).sort();
const want = ['README.md', 'dist/index.d.ts', 'dist/index.js', 'dist/tassel.wasm', 'package.json'];
let failures = 0;
for (const f of want) {
  if (!files.includes(f)) { console.log(`FAIL pack: ${f} is not in the package`); failures++; }
}
for (const f of files) {
  if (!want.includes(f)) { console.log(`FAIL pack: ${f} should not be in the package`); failures++; }
}
console.log(`npm pack --dry-run: ${files.join(', ')}`);
console.log(failures ? `pack: ${failures} FAILED` : 'pack: all passed');
process.exit(failures ? 1 : 0);
