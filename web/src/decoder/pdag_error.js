// The one error a .pdag decode throws. `code` is what the caller can act on:
//   'Corrupt'       the bytes contradict the format (the C++ reader's kCorrupt, kTruncated, kMalformed),
//   'ResourceLimit' the file asks for more than the decoder's limits allow,
//   'Unsupported'   a real part of the format this decoder does not read (zstd, image codecs, another major version).
export class PdagError extends Error {
  constructor(code, detail) {
    super(`${code}: ${detail}`);
    this.name = 'PdagError';
    this.code = code;
    this.detail = detail;  // the message without the code
  }
}

export const corrupt = (message) => new PdagError('Corrupt', message);
export const resourceLimit = (message) => new PdagError('ResourceLimit', message);
export const unsupported = (message) => new PdagError('Unsupported', message);
