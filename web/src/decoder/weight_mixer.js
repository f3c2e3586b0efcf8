// Block color stream version 4's weights (proto/PDAG_FORMAT.md §3), as
// codec/pointdag/color/weight_mixer.h codes them, bit for bit: each bit of a weight's bit tree from
// a logistic mix of four young models chosen by (width, node) and by the neighbours' position in
// steps (else 16 + the previous weight; 33 + it for the cells two away), in half steps (else 31 +
// previous; 48 + it two away), the previous weight, and the position in steps with the previous
// weight's relation to it (else 64 + previous; 81 + them two away); mixer weights per (width,
// depth in the tree).
import { MIXER_BIAS, SQUASH_TABLE, STRETCH, mixerDomain, trainMixer } from './logistic.js';
import { newModels, youngP0, youngUpdate } from './range_coder.js';

const MAX_WEIGHT_BITS = 4;
const NODES = 1 << MAX_WEIGHT_BITS;
const STEP_CONTEXTS = 49;
const HALF_CONTEXTS = 79;
const PREVIOUS_CONTEXTS = 17;
const RELATION_CONTEXTS = 145;
const INPUTS = 4;

function modelRows(contexts) {
  const count = (MAX_WEIGHT_BITS + 1) * contexts * NODES;
  return { p: newModels(count), age: new Uint8Array(count) };
}

export class WeightMixer {
  constructor() {
    this.step = modelRows(STEP_CONTEXTS);
    this.half = modelRows(HALF_CONTEXTS);
    this.previous = modelRows(PREVIOUS_CONTEXTS);
    this.relation = modelRows(RELATION_CONTEXTS);
    this.w = new Int32Array((MAX_WEIGHT_BITS + 1) * MAX_WEIGHT_BITS * (INPUTS + 1));
    for (let k = 0; k < this.w.length; k += INPUTS + 1) {
      this.w[k] = 65536;
      this.w[k + 1] = 19661;
      this.w[k + 2] = 19661;
      this.w[k + 3] = 19661;
    }
  }

  // Decodes a weight of `bits` bits; `position`: WeightContexts.position's result (-1 without
  // neighbours, else far << 16 | step << 8 | half step); `prev`: the previous weight of the block
  // (16 at its first).
  decode(rc, bits, position, prev) {
    const far = position >= 0 && position >> 16 === 1;
    const near = position >= 0 && !far;
    const step = position >= 0 ? (position >> 8) & 0xff : 0;
    const half = position & 0xff;
    const relation = prev === 16 ? 0 : prev === step ? 1 : prev < step ? 2 : 3;
    const r0 = (bits * STEP_CONTEXTS + (near ? step : far ? 33 + step : 16 + prev)) * NODES;
    const r1 = (bits * HALF_CONTEXTS + (near ? half : far ? 48 + half : 31 + prev)) * NODES;
    const r2 = (bits * PREVIOUS_CONTEXTS + prev) * NODES;
    const r3 = (bits * RELATION_CONTEXTS + (near ? step * 4 + relation : far ? 81 + step * 4 + relation : 64 + prev)) * NODES;
    const { step: a, half: b, previous: c, relation: d } = this;
    const w = this.w;
    let node = 1;
    for (let depth = 0; depth < bits; ++depth) {
      const m0 = r0 + node, m1 = r1 + node, m2 = r2 + node, m3 = r3 + node;
      const s0 = STRETCH[4096 - youngP0(a.p, m0)];
      const s1 = STRETCH[4096 - youngP0(b.p, m1)];
      const s2 = STRETCH[4096 - youngP0(c.p, m2)];
      const s3 = STRETCH[4096 - youngP0(d.p, m3)];
      const wi = (bits * MAX_WEIGHT_BITS + depth) * (INPUTS + 1);
      const dot = w[wi] * s0 + w[wi + 1] * s1 + w[wi + 2] * s2 + w[wi + 3] * s3 + w[wi + 4] * MIXER_BIAS;
      const p1 = SQUASH_TABLE[mixerDomain(dot) + 2047];
      const bit = rc.fixedBit(4096 - p1);
      const err = (bit << 12) - p1;
      trainMixer(w, wi, err, s0, s1, s2, s3, MIXER_BIAS);
      youngUpdate(a.p, a.age, m0, bit);
      youngUpdate(b.p, b.age, m1, bit);
      youngUpdate(c.p, c.age, m2, bit);
      youngUpdate(d.p, d.age, m3, bit);
      node = (node << 1) | bit;
    }
    return node - (1 << bits);
  }
}
