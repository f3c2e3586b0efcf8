// The web viewer's tile decoder, as a module worker:
//   new Worker(new URL('./decode_worker.js', import.meta.url), {type: 'module'})
// Messages as decode_service.js describes (contract 2). The WebAssembly build
// (build/web-wasm/pdag_decoder.mjs, copied into the assets by web/build.mjs) is loaded on the first
// 'wasm' request from the URL in this worker's `?wasm=` query parameter, else from
// ./pdag_decoder.mjs beside this script.
import { DecodeService } from './decode_service.js';

const glueUrl = new URL(self.location.href).searchParams.get('wasm') ?? new URL('./pdag_decoder.mjs', import.meta.url).href;
const service = new DecodeService(async () => (await import(glueUrl)).default);

self.onmessage = async ({ data }) => {
  const { reply, transfer } = await service.handle(data);
  self.postMessage(reply, transfer);
};
