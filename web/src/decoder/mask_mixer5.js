// Version 5's mask bits (proto/PDAG_FORMAT.md §2.2), as codec/pointdag/dag/mask_mixer5.h mixes them,
// bit for bit: the version 2 neighbour model, version 4's sides and planes models, the child-level
// pattern model and the side model mixed by integer logistic mixing (weights per child and any bit
// set so far), then refined by an APM interpolated between 33 buckets and averaged 3:1 with the mix.
import { MIXER_BIAS, SQUASH_TABLE, STRETCH, mixerDomain, squash, trainMixer } from './logistic.js';
import { compactP0, compactUpdate, newModels, youngP0, youngUpdate } from './range_coder.js';
import { PATTERN_COUNT } from './spatial_context.js';

const APM_CONTEXTS = 8 * 8 * 8 * 4;

// Where each (class group, child) block of the pattern model starts (kPatternBase).
export const PATTERN_BASE = new Int32Array(3 * 8 + 1);
{
  let at = 0;
  for (let k = 0; k < 24; ++k) {
    PATTERN_BASE[k] = at;
    at += 1 << (PATTERN_COUNT[k & 7] + 3);
  }
  PATTERN_BASE[24] = at;
}

const APM_START = Uint16Array.from({ length: 33 }, (_, j) => {
  const p = squash((j - 16) * 128);
  return 16 * (p < 1 ? 1 : p > 4095 ? 4095 : p);
});

export class MaskMixer5 {
  // `version`: the geometry stream's, 5 or 8 (8 starts the weights at 0.3 and 0.2, not 1 and 0.3).
  constructor(version) {
    this.sides = newModels(256 * 64);
    this.sidesAge = new Uint8Array(256 * 64);
    this.planes = newModels(256 * 27);
    this.planesAge = new Uint8Array(256 * 27);
    this.pattern = new Uint16Array(PATTERN_BASE[24]).fill(32768);
    this.patternAge = new Uint8Array(PATTERN_BASE[24]);
    this.side = newModels(8 * 2 * 128);
    this.sideAge = new Uint8Array(8 * 2 * 128);
    this.apm = new Uint16Array(APM_CONTEXTS * 33);
    for (let k = 0; k < APM_CONTEXTS; ++k) this.apm.set(APM_START, 33 * k);
    this.w = new Int32Array(16 * 6);
    const start = version >= 8 ? [19661, 13107, 13107, 13107, 13107, 0] : [65536, 19661, 19661, 19661, 19661, 0];
    for (let k = 0; k < this.w.length; k += 6) this.w.set(start, k);
  }
  // Decodes child c's bit; `young`/`age`/`m`: the version 2 model; `faces`: bits 0..2 the node's
  // lower x, y, z face neighbours exist, 3..5 the upper; `plane`: the plane memory's state (0..26);
  // `pattern`: the pattern model's index; `side`: the 7 neighbours on c's side; `apm`: the APM's context.
  bit(rc, young, age, m, c, soFar, ones, faces, plane, pattern, side, apm) {
    const t = (1 << c) | soFar;
    const f = (t << 6) | faces;
    const g = t * 27 + plane;
    const q = (c * 2 + (ones ? 1 : 0)) * 128 + side;
    const wi = (c * 2 + (ones ? 1 : 0)) * 6;
    const w = this.w;
    const s0 = STRETCH[4096 - youngP0(young, m)];
    const s1 = STRETCH[4096 - youngP0(this.sides, f)];
    const s2 = STRETCH[4096 - youngP0(this.planes, g)];
    const s3 = STRETCH[4096 - compactP0(this.pattern, pattern)];
    const s4 = STRETCH[4096 - youngP0(this.side, q)];
    const dot = w[wi] * s0 + w[wi + 1] * s1 + w[wi + 2] * s2 + w[wi + 3] * s3 + w[wi + 4] * s4 + w[wi + 5] * MIXER_BIAS;
    const d = mixerDomain(dot);
    const p1 = SQUASH_TABLE[d + 2047];
    const x = d + 2048;
    const near = x & 127;
    const a = apm * 33 + (x >> 7);
    const table = this.apm;
    const refined = (table[a] * (128 - near) + table[a + 1] * near) >> 11;
    let p = (p1 + 3 * refined + 2) >> 2;
    if (p < 1) p = 1;
    else if (p > 4095) p = 4095;
    const bit = rc.fixedBit(4096 - p);
    const target = bit ? 65535 : 0;
    table[a] += (((target - table[a]) >> 6) * (128 - near)) >> 7;
    table[a + 1] += (((target - table[a + 1]) >> 6) * near) >> 7;
    const err = (bit << 12) - p1;
    trainMixer(w, wi, err, s0, s1, s2, s3, s4, MIXER_BIAS);
    youngUpdate(young, age, m, bit);
    youngUpdate(this.sides, this.sidesAge, f, bit);
    youngUpdate(this.planes, this.planesAge, g, bit);
    compactUpdate(this.pattern, this.patternAge, pattern, bit);
    youngUpdate(this.side, this.sideAge, q, bit);
    return bit;
  }
}
