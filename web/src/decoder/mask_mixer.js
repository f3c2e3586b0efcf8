// Version 3's mask bits (proto/PDAG_FORMAT.md §2.2), as codec/pointdag/dag/mask_mixer.h mixes them,
// bit for bit: the version 2 neighbour model's prediction mixed with those of (class, mask so far)
// (mask so far) and (child, parent's mask, lower neighbours) by integer logistic mixing, weights
// learnt per (child, any bit set so far); one set for all classes, fresh per stream. Version 4
// mixes two more: (mask so far, which of the node's six face neighbours exist) and (mask so far,
// the child's plane memory state).
import { MIXER_BIAS, SQUASH_TABLE, STRETCH, mixerDomain, trainMixer } from './logistic.js';
import { newModels, youngP0, youngUpdate } from './range_coder.js';


export class MaskMixer {
  // `more`: version 4's two models; without them their inputs stay 0 (version 3).
  constructor(more) {
    this.tree = newModels(256);
    this.treeAge = new Uint8Array(256);
    this.par = newModels(8 * 256 * 8);
    this.parAge = new Uint8Array(8 * 256 * 8);
    this.more = more;
    this.sides = newModels(more ? 256 * 64 : 0);
    this.sidesAge = new Uint8Array(more ? 256 * 64 : 0);
    this.planes = newModels(more ? 256 * 27 : 0);
    this.planesAge = new Uint8Array(more ? 256 * 27 : 0);
    this.w = new Int32Array(8 * 2 * 6);
    for (let k = 0; k < this.w.length; k += 6) {
      this.w[k] = 65536;
      this.w[k + 1] = 19661;
      this.w[k + 2] = 19661;
      this.w[k + 4] = 19661;
      this.w[k + 5] = 19661;
    }
  }
  // Decodes child c's bit; `young`/`age`/`m`: the version 2 model; `faces`: bits 0..2 the node's
  // lower x, y, z face neighbours exist, 3..5 the upper; `plane`: the plane memory's state (0..26).
  bit(rc, young, age, m, c, soFar, parent, lower, ones, faces, plane) {
    const t = (1 << c) | soFar;
    const q = (c * 256 + parent) * 8 + lower;
    const f = (t << 6) | faces;
    const g = t * 27 + plane;
    const wi = (c * 2 + (ones ? 1 : 0)) * 6;
    const w = this.w;
    const s0 = STRETCH[4096 - youngP0(young, m)];
    const s1 = STRETCH[4096 - youngP0(this.tree, t)];
    const s2 = STRETCH[4096 - youngP0(this.par, q)];
    const s3 = this.more ? STRETCH[4096 - youngP0(this.sides, f)] : 0;
    const s4 = this.more ? STRETCH[4096 - youngP0(this.planes, g)] : 0;
    const dot = w[wi] * s0 + w[wi + 1] * s1 + w[wi + 2] * s2 + w[wi + 3] * MIXER_BIAS + w[wi + 4] * s3 + w[wi + 5] * s4;
    const p1 = SQUASH_TABLE[mixerDomain(dot) + 2047];
    const bit = rc.fixedBit(4096 - p1);
    const err = (bit << 12) - p1;
    trainMixer(w, wi, err, s0, s1, s2, MIXER_BIAS, s3, s4);
    youngUpdate(young, age, m, bit);
    youngUpdate(this.tree, this.treeAge, t, bit);
    youngUpdate(this.par, this.parAge, q, bit);
    if (this.more) {
      youngUpdate(this.sides, this.sidesAge, f, bit);
      youngUpdate(this.planes, this.planesAge, g, bit);
    }
    return bit;
  }
}
