// What the decode worker does with one message (contract 2 of the web viewer), apart from the
// worker's globals so that Node can test it:
//   in:  {id, bytes: ArrayBuffer, backend?: 'js' | 'wasm'}
//   out: {id, ok: true, backend, count, depth, voxelSize, origin, coords, colors, decodeMs} with
//        coords' and colors' buffers to transfer, or {id, ok: false, error, code}.
// The default backend is the faster one in a browser's worker (web/bench/worker_bench.mjs, headless
// Chromium 156: the WebAssembly build ~15% ahead on lion's tiles; under Node 20 the two are even,
// web/bench/decode_bench.mjs). Both give identical voxels. A default that cannot load falls back to
// the JavaScript decoder.
import { decodePdag } from './decode_pdag.js';
import { WasmDecoder } from './wasm_decoder.js';

export const DEFAULT_BACKEND = 'wasm';

export class DecodeService {
  // `loadWasmFactory`: async () => the default export of pdag_decoder.mjs.
  constructor(loadWasmFactory, defaultBackend = DEFAULT_BACKEND) {
    this.loadWasmFactory = loadWasmFactory;
    this.defaultBackend = defaultBackend;
    this.wasm = null;  // a promise of the WasmDecoder
  }

  async wasmDecoder() {
    const current = this.wasm && (await this.wasm.catch(() => null));
    if (!current || current.broken) {  // first use, a failed load, or an abort (out of memory)
      this.wasm = this.loadWasmFactory().then((factory) => WasmDecoder.create(factory));
    }
    return this.wasm;
  }

  async handle({ id, bytes, backend }) {
    try {
      let chosen = backend ?? this.defaultBackend;
      if (chosen !== 'js' && chosen !== 'wasm') throw new Error(`unknown decoder backend '${chosen}' (js or wasm)`);
      let wasm = null;
      if (chosen === 'wasm') {
        try {
          wasm = await this.wasmDecoder();
        } catch (err) {
          if (backend) throw new Error(`the WebAssembly decoder does not load: ${err.message ?? err}`);
          chosen = 'js';  // a default that cannot load: the JavaScript decoder reads every tile too
          this.defaultBackend = 'js';
        }
      }
      const input = new Uint8Array(bytes);
      const start = performance.now();
      const r = wasm ? wasm.decode(input) : decodePdag(input);
      const decodeMs = performance.now() - start;
      const reply = {
        id, ok: true, backend: chosen, count: r.count, depth: r.depth, voxelSize: r.voxelSize, origin: r.origin,
        coords: r.coords, colors: r.colors, decodeMs,
      };
      return { reply, transfer: r.colors ? [r.coords.buffer, r.colors.buffer] : [r.coords.buffer] };
    } catch (err) {
      return { reply: { id, ok: false, error: String(err?.message ?? err), code: err?.code ?? null }, transfer: [] };
    }
  }
}
