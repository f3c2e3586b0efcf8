// A pool of decode workers (contract 2 of the web brief): each tile's bytes are transferred to the
// least busy worker, which answers {id, ok, backend, count, depth, voxelSize, origin, coords, colors, decodeMs}.
export class DecoderPool {
  // backend: 'js' | 'wasm' | undefined (the worker's default, the faster one).
  constructor(workerUrl, size, backend) {
    this.backend = backend;
    this.nextId = 1;
    this.pending = new Map(); // id -> {resolve, reject, worker}
    this.workers = [];
    this.decoded = 0;
    this.decodeMs = 0;
    this.decodedVoxels = 0;
    this.backendUsed = null; // what the workers report they decoded with ('js' | 'wasm')
    this.error = null;
    for (let i = 0; i < size; ++i) {
      const worker = new Worker(workerUrl, { type: 'module' });
      worker.busy = 0;
      worker.onmessage = (e) => this.answer(worker, e.data);
      worker.onerror = (e) => this.fail(worker, `the decode worker failed: ${e.message || 'it could not start'}`);
      this.workers.push(worker);
    }
  }

  // Resolves with the decoded tile; the ArrayBuffer is transferred (unusable afterwards).
  decode(bytes) {
    const worker = this.workers.reduce((a, b) => (b.busy < a.busy ? b : a));
    if (worker.busy === Infinity) return Promise.reject(new Error(this.error));
    const id = this.nextId++;
    worker.busy++;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject, worker });
      const message = { id, bytes };
      if (this.backend) message.backend = this.backend;
      worker.postMessage(message, [bytes]);
    });
  }

  answer(worker, msg) {
    const job = this.pending.get(msg.id);
    if (!job) return;
    this.pending.delete(msg.id);
    worker.busy--;
    if (!msg.ok) {
      job.reject(new Error(msg.error));
      return;
    }
    this.decoded++;
    this.decodeMs += msg.decodeMs;
    this.decodedVoxels += msg.count;
    this.backendUsed = msg.backend;
    job.resolve(msg);
  }

  // A worker that cannot run fails every job it holds.
  fail(worker, message) {
    this.error = message;
    for (const [id, job] of this.pending) {
      if (job.worker !== worker) continue;
      this.pending.delete(id);
      worker.busy--;
      job.reject(new Error(message));
    }
    worker.busy = Infinity; // no more jobs for it
  }

  dispose() {
    for (const w of this.workers) w.terminate();
  }
}
