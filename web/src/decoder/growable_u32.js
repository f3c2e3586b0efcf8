// A Uint32Array that grows by doubling: child lists whose length is known only once decoded.
export class GrowableU32 {
  constructor(capacity) {
    this.a = new Uint32Array(Math.max(16, capacity));
    this.n = 0;
  }
  push(v) {
    if (this.n === this.a.length) {
      const bigger = new Uint32Array(2 * this.a.length);
      bigger.set(this.a);
      this.a = bigger;
    }
    this.a[this.n++] = v;
  }
  done() {
    return this.a.subarray(0, this.n);
  }
}
