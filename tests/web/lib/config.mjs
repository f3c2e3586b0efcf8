// Where the web and browser tests find the built binaries, the viewer and the real scans:
// environment variables (set for ctest by tests/web/ and tests/browser/CMakeLists.txt), else the
// places a checkout builds them. A missing file is a failure with a message, never a silent skip.
import { existsSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../../..');

export const config = {
  root,
  pointdagd: process.env.POINTDAGD || join(root, 'build/server/pointdagd'),
  cli: process.env.POINTDAG_CLI || join(root, 'build/tools/pointdag'),
  dataDir: process.env.POINTDAG_DATA_DIR || join(root, '../shared/data'),
  // The viewer bundled by web/build.mjs, which the browser tests have pointdagd serve.
  webDir: process.env.POINTDAG_WEB_DIR || join(root, 'build/web'),
  // Empty when CMake found no em++ (the WebAssembly decoder was not built).
  wasmDecoder: process.env.POINTDAG_WASM_DECODER ?? join(root, 'build/web-wasm/pdag_decoder.mjs'),
};

export function requireFile(path, what) {
  if (!existsSync(path)) throw new Error(`${what} not found at ${path}`);
  return path;
}

export function scan(name) {
  return requireFile(join(config.dataDir, name), `real scan ${name} (set POINTDAG_DATA_DIR to the folder of ../shared/data)`);
}

// The WebAssembly decoder, or null when the build skipped it (no em++): callers report the skip.
export async function loadWasm() {
  if (!config.wasmDecoder) return null;
  const { WasmDecoder } = await import('../../../web/src/decoder/wasm_decoder.js');
  const factory = (await import(requireFile(config.wasmDecoder, 'the WebAssembly decoder (build it: scripts/build)'))).default;
  return WasmDecoder.create(factory);
}

export const WASM_SKIPPED = 'em++ was not found when configuring, so the WebAssembly decoder was not built (scripts/setup installs emscripten)';
