// Node's side of the tests: the ProgressEvent three's loader needs, and the test files.
import fs from 'node:fs';
import path from 'node:path';
import { loadGltfBytes, THREE } from './gltf.mjs';

// Node 20 lacks ProgressEvent, which three's FileLoader constructs while reading data: URIs.
if (typeof globalThis.ProgressEvent === 'undefined') {
  globalThis.ProgressEvent = class ProgressEvent extends Event {
    constructor(type, init = {}) {
      super(type);
      this.lengthComputable = !!init.lengthComputable;
      this.loaded = init.loaded ?? 0;
      this.total = init.total ?? 0;
    }
  };
}

export const testdata = path.resolve(path.dirname(new URL(import.meta.url).pathname), '../../../shared/testdata');

/** The VRM files of ../shared/testdata/vrm (none, said aloud, when the folder is missing;
 *  an error when TASSEL_REQUIRE_TESTDATA is set). */
export function vrmFiles() {
  const dir = path.join(testdata, 'vrm');
  if (!fs.existsSync(dir)) {
    if (process.env.TASSEL_REQUIRE_TESTDATA) throw new Error(`${dir} is missing and TASSEL_REQUIRE_TESTDATA is set`);
    console.log(`SKIPPED: ${dir} is missing (CI has shared/ beside the clone)`);
    return [];
  }
  return fs.readdirSync(dir).filter((f) => f.endsWith('.vrm')).sort().map((f) => path.join(dir, f));
}

/** A file's GLTFLoader result (see gltf.mjs). */
export function loadGltf(file) {
  return loadGltfBytes(fs.readFileSync(file));
}

export { THREE };
