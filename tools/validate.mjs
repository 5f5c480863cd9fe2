// Validates a glTF/GLB file with the Khronos glTF validator.
// Prints the numbers of errors and warnings and the error messages; exits 1 on errors.
import { validateBytes } from 'gltf-validator';
import { readFileSync } from 'node:fs';

const file = process.argv[2];
const report = await validateBytes(new Uint8Array(readFileSync(file)), { maxIssues: 200 });
const errors = report.issues.messages.filter((m) => m.severity === 0);
console.log(JSON.stringify({
  errors: report.issues.numErrors,
  warnings: report.issues.numWarnings,
  messages: errors.map((m) => `${m.code} ${m.pointer ?? ''} ${m.message}`),
}));
process.exit(report.issues.numErrors > 0 ? 1 : 0);
