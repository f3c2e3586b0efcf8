// The C++ tile decoder compiled to WebAssembly (web/wasm, built by CMake into
// build/web-wasm/pdag_decoder.mjs), behind the same interface as decodePdag: the same result
// object, the same PdagError codes. The bytes are copied into the module's heap and the results out
// of it (the heap is reused by the next decode, and the results must be transferable).
import { DEFAULT_LIMITS } from './decode_pdag.js';
import { PdagError, resourceLimit } from './pdag_error.js';

const CODES = [null, 'Corrupt', 'ResourceLimit', 'Unsupported'];
const UTF8 = new TextDecoder();

export class WasmDecoder {
  // `createModule`: the default export of pdag_decoder.mjs (an emscripten MODULARIZE factory).
  static async create(createModule) {
    return new WasmDecoder(createModule, await createModule());
  }

  constructor(createModule, module) {
    this.createModule = createModule;
    this.module = module;
    // Set when the module aborted (out of memory): it cannot run again; make a new one (create).
    this.broken = false;
  }

  decode(bytes, limits = DEFAULT_LIMITS) {
    const { maxVoxels, maxNodes } = { ...DEFAULT_LIMITS, ...limits };
    if (this.broken) throw resourceLimit('the WebAssembly decoder aborted earlier; create a new one');
    const m = this.module;
    const input = m._malloc(Math.max(1, bytes.length));
    if (!input) throw resourceLimit(`the WebAssembly heap cannot hold a ${bytes.length}-byte tile`);
    let r;
    try {
      m.HEAPU8.set(bytes, input);
      r = m._pdag_decode(input, bytes.length, maxVoxels, maxNodes);
    } catch (err) {
      this.broken = true;
      throw resourceLimit(`the WebAssembly decoder aborted (out of memory?): ${err.message ?? err}`);
    } finally {
      if (!this.broken) m._free(input);
    }
    try {
      const text = (ptr, length) => UTF8.decode(m.HEAPU8.subarray(ptr, ptr + length));
      const code = m._pdag_result_code(r);
      if (code !== 0) throw new PdagError(CODES[code], text(m._pdag_result_message(r), m._pdag_result_message_length(r)));
      const depth = m._pdag_result_depth(r);
      const count = m._pdag_result_count(r);
      const coordsAt = m._pdag_result_coords(r);
      // The heap may have grown during the decode: take its views now.
      const coords = depth > 16 ? new Uint32Array(m.HEAPU8.buffer, coordsAt, 3 * count).slice()
                                : new Uint16Array(m.HEAPU8.buffer, coordsAt, 3 * count).slice();
      const colorsAt = m._pdag_result_colors(r);
      return {
        meta: JSON.parse(text(m._pdag_result_meta(r), m._pdag_result_meta_length(r))),
        depth,
        voxelSize: m._pdag_result_voxel_size(r),
        origin: [0, 1, 2].map((a) => m._pdag_result_origin(r, a)),
        count,
        coords,
        colors: colorsAt ? m.HEAPU8.slice(colorsAt, colorsAt + 3 * count) : null,
      };
    } finally {
      m._pdag_result_free(r);
    }
  }
}
